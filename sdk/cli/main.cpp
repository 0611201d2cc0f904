// blvd: the command line tool. bake (OSM -> package), pack (inspect, verify,
// extract), view (render frames headless).
#include <cstdio>

#include "blvd/blvd.h"
#include "cli/commands.h"
#include "core/log.h"
#include "core/status.h"

int main(int argc, char** argv) {
  CLI::App app{"blvd: street-level city rendering for in-vehicle displays and simulators"};
  app.set_version_flag("--version", blvd_version_string());
  app.require_subcommand(1);
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "debug logging");
  blvd::cli::Runner run;
  blvd::cli::addBake(app, run);
  blvd::cli::addPack(app, run);
  blvd::cli::addView(app, run);
  blvd::cli::addBench(app, run);
#ifdef BLVD_HAVE_GNSS_ADAPTER
  blvd::cli::addNmea(app, run);
#endif
#ifdef BLVD_HAVE_CAN_ADAPTER
  blvd::cli::addCan(app, run);
#endif
  CLI11_PARSE(app, argc, argv);
  if (verbose) blvd::core::setLogLevel(blvd::core::LogLevel::Debug);
  try {
    return run ? run() : 2;
  } catch (const blvd::core::Error& e) {
    std::fprintf(stderr, "blvd: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "blvd: internal error: %s\n", e.what());
    return 3;
  }
}
