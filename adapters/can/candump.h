// candump log files (can-utils `candump -l`), read as a stream and written back.
//
//   (1533198887.123456) can0 123#DEADBEEF        classic CAN, 11-bit id (3 hex digits)
//   (1533198887.123456) can0 12345678#00         29-bit id (8 hex digits)
//   (1533198887.123456) can0 123#R  123#R4       remote request, optional length digit
//   (1533198887.123456) can0 123##5DEADBEEF      CAN FD: '##', flags nibble, up to 64 bytes
//   (1533198887.123456) can0 20000004#0004...    error frame: CAN_ERR_FLAG in the 8-digit id
//   (1533198887.123456) can0 123#11223344556677889_B   8 bytes with a raw DLC of 9..15 ('_')
//
// The grammar is can-utils' parse_canframe()/sprint_canframe() (lib.c). The reader
// also takes what that parser takes (lowercase hex, '.' between bytes, 'r'), and
// writes the canonical spelling, so the round trip is byte-identical for every line
// in the spelling candump writes, including a timestamp that is not zero-padded to
// ten digits and interface names right-aligned by candump when it logs several.
//
// Errors never throw: a bad line is reported with its number and reason and
// skipped; the next call goes on with the next line.
#pragma once

#include <cstdint>
#include <fstream>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "blvd/blvd.h"
#include "can/frame.h"

namespace blvd::can {

// A frame plus what its log line spelled that the frame cannot hold, so that
// writing a record read from a log gives back the same bytes.
struct Record {
  Frame frame;             // frame.t = sec + frac / 10^frac_digits
  int64_t sec = 0;         // integer part of the timestamp
  uint32_t frac = 0;       // fractional digits as an integer: 123456 for ".123456"
  uint8_t frac_digits = 6; // 1..9; candump writes microseconds
  uint8_t sec_width = 10;  // zero-padded width of `sec`; candump writes %010
  uint8_t iface_width = 0; // right-aligned width of the interface column (0: no padding)
  char direction = 0;      // 'R' or 'T' when the line ended in candump -x's RX/TX marker
  uint64_t line = 0;       // 1-based line number in its source; 0 when not read from a log
};

// Parses "123#DEADBEEF" (the part after the interface) into `out` (t and iface
// untouched). False with `reason` set when the text is not a frame.
bool parseFrame(std::string_view text, Frame& out, std::string& reason);

// Parses one log line, without its newline (a trailing '\r' is ignored).
bool parseLine(std::string_view line, Record& out, std::string& reason);

// "123#DEADBEEF", as sprint_canframe() writes it (uppercase, no separators).
std::string formatFrame(const Frame& f);

// The line for a record, without the newline; byte-identical to a line the record was parsed from.
std::string formatLine(const Record& r);

// The canonical candump -l line for a frame: "(%010llu.%06u) iface frame".
// `default_iface` stands in for an empty frame.iface.
std::string formatLine(const Frame& f, std::string_view default_iface = "can0");

// Reads a candump log one line at a time; memory stays bounded by the longest
// accepted line (kMaxLine), whatever the size of the log.
class CandumpReader {
 public:
  static constexpr size_t kMaxLine = 1024;  // the longest valid line is ~200 characters

  enum class Result {
    Frame,    // `out` holds the next frame
    BadLine,  // error() names the line and the reason; the line was skipped
    End,      // no more input
    IoError,  // the stream failed; error() says so. Nothing more will be read.
  };

  // Opens a file for reading. BLVD_ERR_IO with error() set when it cannot be opened.
  blvd_status open(const std::string& path);
  // Reads from a stream the caller keeps alive until the reader is done.
  // `name` is used in messages (a path, "<stdin>").
  void attach(std::istream& in, std::string name);

  Result next(Record& out);

  // "name:line: reason" for the last BadLine or IoError.
  const std::string& error() const { return error_; }
  uint64_t lineNumber() const { return line_; }
  uint64_t frameCount() const { return frames_; }
  uint64_t badLineCount() const { return bad_lines_; }

 private:
  // Next line into line_buf_; false at end of input. Sets too_long_ for an over-long line.
  bool readLine();
  bool fill();

  std::unique_ptr<std::ifstream> file_;
  std::istream* in_ = nullptr;
  std::string name_;
  std::vector<char> buf_;
  size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  std::string line_buf_;
  bool too_long_ = false;
  uint64_t line_ = 0, frames_ = 0, bad_lines_ = 0;
  std::string error_;
};

// Writes candump -l lines to a stream (or a file it opens).
class CandumpWriter {
 public:
  CandumpWriter() = default;
  explicit CandumpWriter(std::ostream& out) : out_(&out) {}

  // Creates (truncates) a file. BLVD_ERR_IO with `err` set when it cannot.
  blvd_status open(const std::string& path, std::string& err);

  // Appends one line. False when the stream has failed.
  bool write(const Record& r);
  bool write(const Frame& f);
  bool flush();

  // Interface written for frames without one.
  std::string default_iface = "can0";

 private:
  std::unique_ptr<std::ofstream> file_;
  std::ostream* out_ = nullptr;
};

}  // namespace blvd::can
