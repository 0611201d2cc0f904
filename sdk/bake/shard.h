// A bake spread over machines: `blvd bake --shard I/N` writes shard files,
// `blvd pack merge` joins them into the package a single bake would have
// written, byte for byte (docs/cluster-bake.md).
//
// A shard file is a package container (package/format.h) holding what every
// shard computes alike (graph, cells, blocks and their blobs, META), its own
// streets' visibility and impostor tables and blobs, and a SHRD section: the
// manifest below, as JSON. The runtime refuses a shard (stream::City::open).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::bake {

// Which shard a bake writes: index of count (count 0: not sharded).
struct ShardSpec {
  uint32_t index = 0, count = 0;
};

// Reads `--shard SPEC` and `--shards N`: "I/N"; "I" with shards N; or "env",
// where the index is SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX (Kubernetes
// Indexed Jobs) and the count --shards N, else SLURM_ARRAY_TASK_COUNT.
// `env` is getenv's shape (tests pass their own). Throws
// core::Error(InvalidArg) saying what is missing or out of range.
ShardSpec parseShardSpec(const std::string& spec, uint32_t shards, const char* (*env)(const char*));

struct ShardManifest {
  uint32_t version = 1;
  uint32_t index = 0, count = 0;
  std::string input_name, input_sha256, options_sha256, generator;
  uint64_t input_bytes = 0;
  uint32_t block_blobs = 0;           // blobs 0 .. block_blobs-1 are the blocks' and the terrain's, the rest this shard's impostors
  std::vector<uint32_t> streets;      // this shard's streets (lower half-edges), ascending
  uint64_t plan_streets = 0;          // streets of all shards together
  std::string plan_sha256;            // of every shard's street list: the same plan in every shard
  std::vector<double> plan_costs;     // estimated cost per shard (shard_plan.h)
  uint64_t blocks_drawn = 0;          // blocks its rigs drew (within reach of its streets)
  double seconds = 0, cpu_seconds = 0;  // this shard's bake, wall and CPU (all threads), before writing
};

std::string manifestJson(const ShardManifest& m);
// Throws core::Error(Corrupt) naming `name` and the field that is missing,
// of the wrong type or out of range.
ShardManifest parseManifest(const std::string& json, const std::string& name);

// SHA-256 of the plan: every shard's street list, in shard order.
std::string planDigest(const std::vector<std::vector<uint32_t>>& plan);

struct MergeShardLine {
  std::string path;
  ShardManifest manifest;
  uint64_t bytes = 0;
  uint32_t cells = 0;  // cells with impostors
};

struct MergeSummary {
  std::vector<MergeShardLine> shards;  // in shard order
  uint64_t package_bytes = 0;
  double seconds = 0;
  double imbalance = 0;       // slowest shard's seconds / the mean
  double cpu_seconds = 0;     // all shards together
};

// Checks that `paths` are the shards 0..N-1 of one bake (same input bytes,
// options, generator and plan; each street in exactly one shard; the shared
// sections identical) and writes the package to `out` (temporary name, then
// renamed). Throws core::Error naming the shard and the reason otherwise.
MergeSummary mergeShards(const std::vector<std::string>& paths, const std::string& out);

}  // namespace blvd::bake
