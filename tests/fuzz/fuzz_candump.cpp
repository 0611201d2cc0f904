// Fuzz target for the candump log reader (adapters/can): any input must give
// frames or bad lines with a "name:line: reason" message, never a crash, a
// leak or undefined behaviour; and every frame it reads must write back to a
// line that reads again as the same frame (the writer's round trip).
//
// Seeds: set BLVD_FUZZ_SEED_DIR and the target writes a log with every frame
// kind there before running; add tests/data/can/candump as well.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "can/candump.h"

namespace {

using blvd::can::CandumpReader;
using blvd::can::Frame;
using blvd::can::Record;

bool sameFrame(const Frame& a, const Frame& b) {
  return a.id == b.id && a.extended == b.extended && a.rtr == b.rtr && a.error == b.error && a.fd == b.fd &&
         a.fd_flags == b.fd_flags && a.dlc == b.dlc && a.len8_dlc == b.len8_dlc && a.iface == b.iface &&
         std::memcmp(a.data, b.data, sizeof a.data) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (!dir || !*dir) return 0;
  std::filesystem::create_directories(dir);
  std::ofstream(std::filesystem::path(dir) / "seed_kinds.log")
      << "(1533198887.123456) can0 123#DEADBEEF\n(1533198887.123457) can0 12345678#00\n"
         "(1533198887.123460) can0 123#R4\n(1533198887.123461) can0 1FFFFFFF#R8_9\n"
         "(1533198887.123462) can1 123##5DEADBEEF\n(1533198887.123463) can0 20000004#0004000000000000\n"
         "(1533198887.123464) can0 123#1122334455667788_B\n(46408.584930)   can128 2E4#BE000000A9 R\n"
         "(1.123456789) can0 7FF#de.ad\r\n";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::istringstream in(text);
  CandumpReader reader;
  reader.attach(in, "fuzz");
  Record r;
  for (;;) {
    const CandumpReader::Result res = reader.next(r);
    if (res == CandumpReader::Result::End) break;
    if (res != CandumpReader::Result::Frame) {
      if (reader.error().rfind("fuzz:", 0) != 0) std::abort();  // every failure names the input and line
      if (res == CandumpReader::Result::IoError) break;
      continue;
    }
    if (r.frame.dlc > (r.frame.fd ? 64 : 8)) std::abort();
    // The record's own line reads back as the same frame and writes the same bytes.
    const std::string line = blvd::can::formatLine(r);
    Record again;
    std::string reason;
    if (!blvd::can::parseLine(line, again, reason) || !sameFrame(r.frame, again.frame) ||
        blvd::can::formatLine(again) != line)
      std::abort();
    // The canonical line of the frame alone reads back as the same frame.
    if (!blvd::can::parseLine(blvd::can::formatLine(r.frame), again, reason) || !sameFrame(r.frame, again.frame))
      std::abort();
  }
  // The frame parser alone, on the raw input.
  Frame f;
  std::string reason;
  if (!blvd::can::parseFrame(text, f, reason) && reason.empty()) std::abort();
  return 0;
}
