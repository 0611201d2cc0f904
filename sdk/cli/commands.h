// Subcommands of the `blvd` tool. Each registers its options on the CLI11 app
// and returns the process exit code when run.
#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <string>

#include "blvd/blvd.h"

namespace blvd::cli {

using Runner = std::function<int()>;

// Each adds its subcommand to `app` and sets `run` when it is selected.
void addBake(CLI::App& app, Runner& run);
void addPack(CLI::App& app, Runner& run);
// `blvd pack merge` (cmd_pack_merge.cpp), under `pack`.
void addPackMerge(CLI::App& pack, Runner& run);
void addView(CLI::App& app, Runner& run);
void addBench(CLI::App& app, Runner& run);
// `blvd bench memory` and its per-package child `bench memory-drive`, under `bench`.
void addBenchMemory(CLI::App& bench, Runner& run);
// `blvd bench scale` (cmd_bench_scale.cpp).
void addBenchScale(CLI::App& bench, Runner& run);
// `blvd bench budget` (cmd_bench_budget.cpp).
void addBenchBudget(CLI::App& bench, Runner& run);
// `blvd bench decode` (cmd_bench_decode.cpp).
void addBenchDecode(CLI::App& bench, Runner& run);
// `blvd bench stream` (cmd_bench_stream.cpp).
void addBenchStream(CLI::App& bench, Runner& run);
// `blvd bench track` (cmd_bench_track.cpp), added to `bench` by addBench.
void addBenchTrack(CLI::App& bench, Runner& run);
// "full", "local", "radius:R", "single", "layered"/"blvd" -> mode (+ radius).
bool parseMode(const std::string& s, blvd_render_mode& mode, float& radius);
// Defined in adapters/<x>/cli_<x>.cpp, compiled into the CLI when the adapter exists.
void addNmea(CLI::App& app, Runner& run);
void addCan(CLI::App& app, Runner& run);

}  // namespace blvd::cli
