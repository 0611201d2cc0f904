// Fuzz target for the DBC parser and the signal codec (sdk/vehicle): any input
// must load or fail with "source:line: reason", never crash; for a file that
// loads, decoding a frame made of the input bytes and encoding the values again
// must reproduce every signal bit (encode(decode(frame)) == frame).
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a small DBC with every
// supported construct there; add tests/data/can/dbc (the opendbc files) and
// tests/data/can/dbc_cases (messages that are skipped, multiplexing).
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "vehicle/dbc.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  std::ofstream(std::filesystem::path(dir) / "seed.dbc")
      << "VERSION \"\"\nNS_ :\n    CM_\n    SG_\n\nBS_:\nBU_: A B\n\n"
         "BO_ 37 STEER: 8 A\n SG_ ANGLE : 3|12@0- (1.5,0) [-500|500] \"deg\" B\n"
         " SG_ FRACTION : 39|4@0- (0.1,0) [-0.7|0.7] \"deg\" B\n SG_ WIDE : 0|64@1+ (1,0) [0|0] \"\" B\n\n"
         "BO_ 2147484159 EXT: 8 A\n SG_ MUX M : 0|2@1+ (1,0) [0|3] \"\" B\n SG_ X m1 : 8|8@1+ (1,0) [0|255] \"\" B\n"
         " SG_ F : 32|32@1- (2,1) [0|0] \"\" B,A\n\n"
         "CM_ \"multi\nline\";\nVAL_ 37 ANGLE 0 \"zero\" 1 \"one\" ;\nSIG_VALTYPE_ 2147484159 F : 1;\n";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  blvd::vehicle::Database db;
  std::string err;
  const blvd::core::Status st = db.parse(text, "fuzz.dbc", err);
  if (st != blvd::core::Status::Ok) {
    if (err.rfind("fuzz.dbc:", 0) != 0 || !db.messages().empty()) std::abort();
    return 0;
  }
  for (const auto& d : db.diagnostics())
    if (d.rfind("fuzz.dbc:", 0) != 0) std::abort();
  for (const auto& s : db.skipped())
    if (s.line == 0 || s.reason.empty()) std::abort();
  blvd::vehicle::DbcOptions strict;
  strict.strict = true;
  blvd::vehicle::Database db2;
  // Strict loads exactly when nothing was skipped or left out.
  const bool strict_ok = db2.parse(text, "fuzz.dbc", err, strict) == blvd::core::Status::Ok;
  if (strict_ok && !db.skipped().empty()) std::abort();

  std::vector<blvd::vehicle::DecodedSignal> values;
  size_t n = 0;
  for (const auto& m : db.messages()) {
    if (++n > 256) break;
    if (db.find(m.id, m.extended) != &m) std::abort();
    blvd::vehicle::Frame f;
    f.id = m.id;
    f.extended = m.extended;
    f.dlc = 64;
    f.fd = true;
    for (size_t i = 0; i < 64; ++i) f.data[i] = size ? data[(i * 7 + m.id) % size] : 0;
    blvd::vehicle::decode(m, f, values);
    blvd::vehicle::Frame g;
    g.dlc = f.dlc;
    if (blvd::vehicle::encode(m, values, g, err) != blvd::core::Status::Ok) std::abort();
    uint8_t mask[64] = {};
    for (const auto& v : values) blvd::vehicle::insertRaw(*v.signal, ~uint64_t{0}, mask);
    for (size_t i = 0; i < 64; ++i)
      if ((g.data[i] & mask[i]) != (f.data[i] & mask[i])) std::abort();
  }
  return 0;
}
