// NMEA 0183 stream parser: bytes in, sentences and diagnostics out, and an
// epoch assembler that merges the sentences of one receiver cycle into one Fix.
//
// Three layers, each usable on its own:
//
//   SentenceReader  bytes -> framed, checksum-checked Sentence (or an NmeaDiagnostic)
//   decodeSentence  Sentence -> NmeaRecord (RMC GGA GNS VTG GSA GST GLL ZDA HDT THS)
//   FixAssembler    NmeaRecord stream -> one Fix per epoch (sentences sharing a time)
//
// NmeaDecoder chains the three for the common case:
//
//   struct Out : blvd::gnss::NmeaDecoder::Handler {
//     void onFix(const blvd::gnss::Fix& f) override { ... }
//     void onDiagnostic(const blvd::gnss::NmeaDiagnostic& d) override { log(d.message); }
//   } out;
//   blvd::gnss::NmeaDecoder dec;
//   while (n = read(...)) dec.feed(buf, n, out);
//   dec.finish(out);  // end of input: flushes the last epoch
//
// Contract:
// - Threads: an instance is used by one thread at a time; separate instances are independent.
// - Memory: every buffer is a fixed-size member; feed() and the handlers it calls do not
//   allocate. Views handed to a handler (Sentence fields) are valid only during the call.
// - Errors: bad input never throws. Each rejected sentence or run of garbage yields one
//   NmeaDiagnostic naming its line (1-based, counted in LF bytes) and byte offset
//   (0-based), and the reason. The reader resynchronises on the next '$' or '!', so good
//   data after bad data is never lost.
// - Checksums: a wrong checksum rejects the sentence. A sentence without any '*hh' is
//   accepted, as gpsd does (packet.c: "checksum passed or not present"), and marked
//   (Sentence::has_checksum, Fix kFixNoChecksum); Options can reject those instead.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "gnss/fix.h"

namespace blvd::gnss {

// ---------------------------------------------------------------------------
// Diagnostics

enum class NmeaError : uint8_t {
  None = 0,
  Garbage,            // bytes outside any sentence (not whitespace, not a '#' comment line)
  BadByte,            // a control or non-ASCII byte inside a sentence
  Overlong,           // longer than Options::max_sentence before its line ended
  Truncated,          // a new '$' or the end of the input arrived before the line ended
  BadAddress,         // the address ("GPGGA") is not 3..8 upper-case letters or digits
  BadChecksum,        // '*hh' present and does not match the XOR of the sentence
  MalformedChecksum,  // '*' not followed by exactly two hex digits
  MissingChecksum,    // no '*hh' and Options::require_checksum is set
  TooManyFields,      // more than kMaxFields comma-separated fields
  TooFewFields,       // a supported sentence with fewer fields than it must have
  BadField,           // a field that must be a number, time, date, latitude... is not
};

// Static text for an error code ("bad checksum").
const char* nmeaErrorString(NmeaError e);

struct NmeaDiagnostic {
  NmeaError code = NmeaError::None;
  uint64_t line = 0;     // 1-based line of the first byte concerned
  uint64_t offset = 0;   // 0-based byte offset of the first byte concerned
  char address[9] = {};  // "GPGGA" when known, else ""
  char message[192] = {};  // "line 12, byte 873: GPGGA: bad checksum: ..." (complete, human-readable)
};

// ---------------------------------------------------------------------------
// Layer 1: framing

struct Sentence {
  static constexpr size_t kMaxFields = 64;

  std::string_view text;     // from '$' (or '!') up to, not including, the line end
  std::string_view address;  // "GPGGA", "PSRFEPE"
  std::string_view talker;   // "GP"; empty for proprietary ('P...') sentences
  std::string_view type;     // "GGA"; for proprietary sentences the whole address after 'P'
  bool proprietary = false;
  bool has_checksum = false;
  uint64_t line = 0;    // 1-based
  uint64_t offset = 0;  // 0-based offset of '$'
  size_t field_count = 0;  // data fields after the address
  std::array<std::string_view, kMaxFields + 1> fields;  // [0] = address, [1..field_count] = data

  // Data field i (1-based, as NMEA documents number them); empty if absent.
  std::string_view field(size_t i) const { return i <= field_count ? fields[i] : std::string_view(); }
};

class SentenceReader {
 public:
  struct Options {
    // Longest sentence accepted, '$' to '*hh' inclusive. NMEA says 82 with CR LF;
    // real receivers exceed it (u-blox GSA with system id, SkyTraq $PSTI: 103).
    size_t max_sentence = 160;
    // Lines whose first byte is '#' are skipped silently (gpsd's logs annotate with them).
    bool skip_hash_comments = true;
    // Reject sentences without '*hh' instead of accepting them (marked) like gpsd.
    bool require_checksum = false;
  };

  class Handler {
   public:
    virtual void onSentence(const Sentence& s) = 0;
    virtual void onDiagnostic(const NmeaDiagnostic& d) = 0;

   protected:
    ~Handler() = default;
  };

  struct Stats {
    uint64_t bytes = 0;
    uint64_t sentences = 0;       // accepted
    uint64_t no_checksum = 0;     // accepted without '*hh'
    uint64_t diagnostics = 0;     // rejected sentences + garbage runs
    uint64_t bad_checksum = 0;
  };

  SentenceReader() : SentenceReader(Options{}) {}
  explicit SentenceReader(const Options& opt);

  // Consumes bytes; calls h for every sentence completed and every problem found.
  void feed(const void* data, size_t size, Handler& h);
  // End of input: a pending sentence is accepted if its checksum is complete and
  // valid (only its line end was missing), else reported as truncated.
  void finish(Handler& h);
  // Forgets any partial sentence and the line/offset counters.
  void reset();

  const Stats& stats() const { return stats_; }
  const Options& options() const { return opt_; }

 private:
  enum class State : uint8_t { Ground, Sentence, Comment, Skip, Garbage };
  void startSentence();
  void complete(Handler& h, bool at_eof_or_dollar);
  void report(Handler& h, NmeaError code, uint64_t line, uint64_t offset, std::string_view address,
              const char* fmt, ...) __attribute__((format(printf, 7, 8)));
  void flushGarbage(Handler& h);

  Options opt_;
  Stats stats_;
  State state_ = State::Ground;
  bool at_line_start_ = true;
  uint64_t line_ = 1;
  uint64_t offset_ = 0;  // offset of the next byte
  // Current sentence.
  uint64_t sent_line_ = 0, sent_offset_ = 0;
  size_t len_ = 0;
  std::array<char, 512> buf_{};
  // Current garbage run.
  uint64_t garbage_line_ = 0, garbage_offset_ = 0, garbage_count_ = 0;
  std::array<char, 24> garbage_preview_{};
  size_t garbage_preview_len_ = 0;
  Sentence sentence_;
  NmeaDiagnostic diag_;
};

// ---------------------------------------------------------------------------
// Layer 2: decoding

enum class SentenceType : uint8_t { Unknown, RMC, GGA, GNS, VTG, GSA, GST, GLL, ZDA, HDT, THS };

// The fields of one supported sentence, converted to SI units. NaN / -1 / '\0'
// mean "not given".
struct NmeaRecord {
  SentenceType type = SentenceType::Unknown;
  char talker[3] = {};
  uint64_t line = 0, offset = 0;
  bool has_checksum = true;

  bool has_tod = false;   // time of day (RMC GGA GNS GLL ZDA GST)
  int64_t tod_ms = 0;     // milliseconds since midnight UTC (sub-ms digits are rounded)
  bool has_date = false;  // RMC ddmmyy, ZDA dd,mm,yyyy
  int year = 0, month = 0, day = 0;

  bool has_pos = false;
  double lat = 0, lon = 0;
  char status = '\0';  // RMC/GLL: 'A' valid, 'V' invalid, 'D' differential
  char faa = '\0';     // FAA mode indicator (RMC GLL VTG GNS first char, THS mode)
  char nav_status = '\0';  // RMC/GNS NMEA 4.1 navigational status ('S','C','U','V')
  int quality = -1;    // GGA fix quality 0..8
  int sats = -1;       // GGA/GNS satellites used
  double hdop = 0, pdop = 0, vdop = 0;  // NaN if absent (set by decodeSentence)
  double alt = 0, geoid_sep = 0;        // metres, NaN if absent
  double speed_mps = 0, track_deg = 0;  // NaN if absent
  int gsa_mode = 0;                     // GSA fix type 1..3, 0 if absent
  // GST: 1-sigma errors in metres.
  double rms = 0, lat_err = 0, lon_err = 0, alt_err = 0;
  double heading_deg = 0;  // HDT/THS
};

// Talkers whose sentences are decoded: GP GN GL GA GB BD GQ (and GI, QZ).
bool isGnssTalker(std::string_view talker);
SentenceType sentenceType(std::string_view type);

// Decodes a framed sentence. Returns false for proprietary, unknown and
// non-GNSS-talker sentences (no diagnostic: they are simply not ours) and for
// malformed ones, in which case *diag is filled (code != None) and the whole
// sentence must be ignored: a field that does not parse means the receiver
// or the line is broken, and a half-read sentence is worse than none.
bool decodeSentence(const Sentence& s, NmeaRecord* rec, NmeaDiagnostic* diag);

// ---------------------------------------------------------------------------
// Layer 3: epochs
//
// An epoch is the run of sentences that share one time of day: a receiver
// emits its RMC, GGA, GSA, GST, ZDA ... of one solution together. Sentences
// without a time (GSA, VTG, HDT, a Quectel RMC with an empty time field)
// belong to the epoch in progress (until a time arrives, a second RMC, GGA,
// GNS, GLL, VTG or ZDA of the same talker starts a new one). The epoch
// closes, and its Fix is emitted, when a sentence with another time
// arrives, on finish(), or - once the assembler has learned the receiver's
// cycle - right after the sentence that ends it (gpsd's "cycle ender"): the
// last decoded sentence (address and occurrence count) before the time changed,
// the same on two consecutive epochs. That removes one cycle of latency.
// Each epoch is emitted once whatever subset of its cycle a receiver sends
// (no GST without a fix, GSA every few cycles): the ender only moves later in
// the cycle, never back to an earlier sentence because some epochs lack the
// last ones; an epoch without the ender closes when the next one begins. Only
// when a decoded sentence follows the ender in the same epoch (the cycle is
// longer than learned: a sentence type not seen there before) is the epoch
// emitted again, completed, with kFixUpdate set, and the ender moves to that
// sentence.
//
// Field rules (chosen to agree with gpsd, which tests/adapters/gnss checks on
// every shared log):
// - time: the epoch's time of day plus the date from an RMC (status A/D) or
//   ZDA of the epoch, else the last such date, plus one day if the time of day
//   went back by more than 12 h (midnight). RMC dates under status V are not
//   trusted: receivers send junk dates before they have a fix (gp-320fw
//   cold boot: 2006, 2010, 1999 within seconds). No date seen yet: no time.
// - validity: the epoch has no fix if any position sentence says so (RMC/GLL
//   status V, GGA quality 0, GNS mode N), if none carried a position, or if
//   the last sentence that states a mode said "no fix": a GSA of fix type 1,
//   or a GGA from fewer than 3 satellites (an empty count reads 0). gpsd lets
//   the last mode-setting sentence of a cycle win (gps_merge_fix); an RMC,
//   GLL, GNS or GGA with a fix after such a GSA gives the fix back.
// - mode: the GSA fix type when a GSA came with the epoch; else 3 when GGA or
//   GNS gave an altitude from 4 or more satellites, or when the last GSA (at
//   most 10 s old) said 3D and the epoch has an altitude or no GGA/GNS at all
//   (gpsd's RMC takes 3D from the satellites the last GSA listed), else 2. A
//   2D GSA does not downgrade a fix whose GGA/GNS altitude came from 4 or
//   more satellites: gpsd keeps 3D there ("don't downgrade mode if holding
//   previous fix"), and Telit PLS83 reports GSA 2 while giving an altitude
//   from 14 satellites.
//   Where gpsd's rule looks at the previous cycle we do not follow it, and
//   tests/adapters/gnss/test_nmea.cpp (ModeAsGpsdDecidesIt) pins both: a 2D
//   receiver that keeps sending an altitude from 3 satellites reads 3D in
//   gpsd from its second epoch on (its RMC sees the previous altitude), 2D
//   here; and when the altitude goes, gpsd reports one more 3D epoch without
//   one, 2D here. Each epoch's mode here is what that epoch's sentences say.
// - position, altitude: the last sentence of the epoch that gave them.
// - speed, track: RMC or VTG; VTG's km/h only when the knots field is empty.
// - errors: GST of the epoch's time (it may come before the GGA it refers to).
class FixAssembler {
 public:
  struct Options {
    bool early_emit = true;  // emit at the learned cycle ender instead of at the next time
  };

  class Handler {
   public:
    virtual void onFix(const Fix& f) = 0;

   protected:
    ~Handler() = default;
  };

  FixAssembler() : FixAssembler(Options{}) {}
  explicit FixAssembler(const Options& opt) : opt_(opt) { reset(); }

  // Every framed sentence, decoded or not, so the cycle can be learned from all of them.
  // `rec` is null for sentences that decodeSentence did not take.
  void add(const Sentence& s, const NmeaRecord* rec, Handler& h);
  // Emits the epoch in progress, if any.
  void flush(Handler& h);
  void reset();

  bool cycleLearned() const { return ender_reliable_; }

 private:
  struct Epoch {
    bool open = false;
    bool has_tod = false;
    int64_t tod_ms = 0;
    bool has_date = false;
    int64_t days = 0;  // date of the epoch from its own RMC/ZDA
    bool any_position_sentence = false;
    bool invalid = false;     // a position sentence said "no fix"
    bool nofix_vote = false;  // the last sentence that states a mode said "no fix" (GSA 1, GGA < 3 satellites)
    bool gga_or_gns = false;  // a usable GGA/GNS came (it would have given any altitude)
    bool has_pos = false;
    double lat = 0, lon = 0;
    bool has_alt = false;
    double alt = 0;
    bool alt_3d = false;  // GGA/GNS altitude with >= 4 satellites
    double geoid_sep = 0;
    bool has_geoid = false;
    int sats = -1;
    int gsa_mode = 0;
    double hdop = 0, pdop = 0, vdop = 0;
    bool has_hdop = false, has_pdop = false;
    double speed = 0, track = 0, heading_deg = 0;
    bool has_speed = false, has_track = false, has_heading = false;
    int gga_status = kStatusUnknown;  // from GGA quality
    int faa_status = kStatusUnknown;  // from the first FAA mode letter (RMC, GNS)
    bool no_checksum = false;

    bool hasFix() const;
    // One sentence's fields into the epoch (apply() picks by type).
    void rmc(const NmeaRecord& r);
    void gga(const NmeaRecord& r);
    void gns(const NmeaRecord& r);
    void gll(const NmeaRecord& r);
    void gsa(const NmeaRecord& r);
    void date(const NmeaRecord& r);
    void heading(const NmeaRecord& r);
    void motion(const NmeaRecord& r);  // speed and track
    void position(const NmeaRecord& r);
    void ggaGns(const NmeaRecord& r);
  };
  struct Gst {
    bool valid = false;
    int64_t tod_ms = 0;
    double lat_err = 0, lon_err = 0, alt_err = 0;
  };
  struct Key {  // address + occurrence count: identifies the cycle ender
    char address[9] = {};
    uint16_t count = 0;
    bool operator==(const Key& o) const;
  };

  void closeEpoch(Handler& h, bool learn);
  void apply(const NmeaRecord& r);
  void applyGst(const NmeaRecord& r);
  Fix build(const Epoch& e) const;
  void buildTime(const Epoch& e, Fix& f) const;
  void buildPosition(const Epoch& e, Fix& f) const;
  void buildErrors(const Epoch& e, Fix& f) const;
  int modeOf(const Epoch& e) const;
  void emit(Handler& h, const Fix& f);
  uint16_t countOf(std::string_view address);
  bool seenInEpoch(std::string_view address) const;
  bool reached(const Key& k) const;  // k's address occurred at least k.count times in this epoch
  static bool onePerCycle(SentenceType t);
  void startEpoch();

  Options opt_;
  Epoch cur_;
  Gst gst_;
  // Date state.
  bool have_date_ = false;
  int64_t last_days_ = 0;
  int64_t last_tod_ms_ = 0;
  // Fix type of the last GSA, for epochs without one.
  int last_gsa_mode_ = 0;
  int64_t last_gsa_tod_ms_ = 0;
  // Cycle learning.
  static constexpr size_t kMaxAddresses = 24;
  std::array<Key, kMaxAddresses> seen_{};  // addresses of the epoch in progress with counts
  size_t seen_n_ = 0;
  Key last_key_{};       // last sentence of the epoch in progress
  Key ender_{};          // learned cycle ender
  Key candidate_{};      // ender seen at the previous close
  bool ender_reliable_ = false;
  // Early emission.
  bool emitted_ = false;  // cur_ was already emitted at its ender
  Fix emitted_fix_{};
};

// ---------------------------------------------------------------------------
// All three layers.

class NmeaDecoder {
 public:
  struct Options {
    SentenceReader::Options reader;
    FixAssembler::Options assembler;
  };

  class Handler : public FixAssembler::Handler {
   public:
    // Every framed sentence (decoded or not) before it is merged; default: ignore.
    virtual void onSentence(const Sentence&, const NmeaRecord*) {}
    virtual void onDiagnostic(const NmeaDiagnostic& d) = 0;

   protected:
    ~Handler() = default;
  };

  NmeaDecoder() : NmeaDecoder(Options{}) {}
  explicit NmeaDecoder(const Options& opt);

  void feed(const void* data, size_t size, Handler& h);
  void finish(Handler& h);  // end of input: last sentence and last epoch
  void reset();

  const SentenceReader::Stats& readerStats() const { return reader_.stats(); }
  uint64_t fixes() const { return fixes_; }
  uint64_t rejected() const { return rejected_; }  // sentences that failed decoding

 private:
  struct Bridge;
  SentenceReader reader_;
  FixAssembler assembler_;
  NmeaRecord rec_;
  uint64_t fixes_ = 0;
  uint64_t rejected_ = 0;
};

}  // namespace blvd::gnss
