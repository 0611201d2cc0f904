// `blvd bench route` (cmd_bench_route.cpp): options and the run.
#pragma once
#include <cstdint>
#include <string>

namespace blvd::cli {

struct RouteBenchOpts {
  std::string package, route = "auto:200", size = "800x480", json_path, html_dir;
  std::string impostor_texture = "rgba8";  // blvd_runtime_desc.impostor_texture: rgba8 or etc2
  uint64_t seed = 1;
  double step = 0;  // metres between poses; 0: one pose per cell (its middle)
  int repeat = 1;   // timed renders per pose and mode (median kept)
  int pictures = 24;
};

// Every pose in every mode; JSON to stdout (and json_path), HTML to html_dir.
int runRouteBench(const RouteBenchOpts& o);

}  // namespace blvd::cli
