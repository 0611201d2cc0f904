// Shard files and their merge; the contract is in shard.h.
#include "bake/shard.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include "bake/digest.h"
#include "core/status.h"

namespace blvd::bake {
namespace {

core::Error badArg(const std::string& what) { return core::Error(core::Status::InvalidArg, what); }

// A whole decimal number below 2^32, or throws naming `what`.
uint32_t parseIndex(const std::string& text, const std::string& what) {
  char* end = nullptr;
  const unsigned long v = std::strtoul(text.c_str(), &end, 10);
  if (text.empty() || text[0] == '-' || *end != '\0' || v > 0xFFFFFFFFul)
    throw badArg(what + ": '" + text + "' is not a whole number");
  return static_cast<uint32_t>(v);
}

}  // namespace

ShardSpec parseShardSpec(const std::string& spec, uint32_t shards, const char* (*env)(const char*)) {
  ShardSpec s;
  const size_t slash = spec.find('/');
  if (spec == "env") {
    const char* id = env("SLURM_ARRAY_TASK_ID");
    const char* from = "SLURM_ARRAY_TASK_ID";
    if (!id) id = env("JOB_COMPLETION_INDEX"), from = "JOB_COMPLETION_INDEX";
    if (!id) throw badArg("--shard env: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set");
    s.index = parseIndex(id, from);
    const char* n = env("SLURM_ARRAY_TASK_COUNT");
    if (shards == 0 && !n) throw badArg("--shard env: give the number of shards with --shards N");
    s.count = shards ? shards : parseIndex(n, "SLURM_ARRAY_TASK_COUNT");
  } else if (slash != std::string::npos) {
    s.index = parseIndex(spec.substr(0, slash), "--shard I/N");
    s.count = parseIndex(spec.substr(slash + 1), "--shard I/N");
    if (shards && shards != s.count)
      throw badArg("--shard " + spec + " and --shards " + std::to_string(shards) + " disagree");
  } else {
    s.index = parseIndex(spec, "--shard I");
    if (shards == 0) throw badArg("--shard " + spec + ": give the number of shards (--shard I/N or --shards N)");
    s.count = shards;
  }
  if (s.count == 0) throw badArg("--shard: the number of shards must be at least 1");
  if (s.index >= s.count)
    throw badArg("--shard: index " + std::to_string(s.index) + " is out of range for " + std::to_string(s.count) +
                 " shards (indices start at 0)");
  return s;
}

std::string manifestJson(const ShardManifest& m) {
  const nlohmann::json j = {
      {"format", "blvd-shard"},
      {"version", m.version},
      {"shard", m.index},
      {"shards", m.count},
      {"input", {{"name", m.input_name}, {"bytes", m.input_bytes}, {"sha256", m.input_sha256}}},
      {"options_sha256", m.options_sha256},
      {"generator", m.generator},
      {"block_blobs", m.block_blobs},
      {"streets", m.streets},
      {"plan", {{"streets", m.plan_streets}, {"sha256", m.plan_sha256}, {"costs", m.plan_costs}}},
      {"blocks_drawn", m.blocks_drawn},
      {"seconds", m.seconds},
      {"cpu_seconds", m.cpu_seconds},
  };
  return j.dump(1);
}

ShardManifest parseManifest(const std::string& json, const std::string& name) {
  const nlohmann::json j = nlohmann::json::parse(json, nullptr, false);
  auto bad = [&](const std::string& why) { return core::Error(core::Status::Corrupt, name + ": shard manifest: " + why); };
  if (j.is_discarded() || !j.is_object()) throw bad("not a JSON object");
  // A count: an unsigned integer that fits (nlohmann's get<> would convert
  // -1 or 1e300 without a word, the second undefined behaviour).
  auto count = [&](const nlohmann::json& v, const char* what, uint64_t max) -> uint64_t {
    if (!v.is_number_unsigned() || v.get<uint64_t>() > max) throw bad(std::string(what) + " is not a count: " + v.dump());
    return v.get<uint64_t>();
  };
  constexpr uint64_t k32 = UINT32_MAX, k64 = UINT64_MAX;
  ShardManifest m;
  try {
    const auto format = j.find("format");
    if (format == j.end() || !format->is_string() || *format != "blvd-shard") throw bad("format is not blvd-shard");
    m.version = static_cast<uint32_t>(count(j.at("version"), "version", k32));
    if (m.version != 1) throw bad("version " + std::to_string(m.version) + " (this blvd reads 1)");
    m.index = static_cast<uint32_t>(count(j.at("shard"), "shard", k32));
    m.count = static_cast<uint32_t>(count(j.at("shards"), "shards", k32));
    m.input_name = j.at("input").at("name").get<std::string>();
    m.input_bytes = count(j.at("input").at("bytes"), "input bytes", k64);
    m.input_sha256 = j.at("input").at("sha256").get<std::string>();
    m.options_sha256 = j.at("options_sha256").get<std::string>();
    m.generator = j.at("generator").get<std::string>();
    m.block_blobs = static_cast<uint32_t>(count(j.at("block_blobs"), "block_blobs", k32));
    for (const nlohmann::json& h : j.at("streets").get_ref<const nlohmann::json::array_t&>())
      m.streets.push_back(static_cast<uint32_t>(count(h, "a street", k32)));
    m.plan_streets = count(j.at("plan").at("streets"), "plan streets", k64);
    m.plan_sha256 = j.at("plan").at("sha256").get<std::string>();
    m.plan_costs = j.at("plan").at("costs").get<std::vector<double>>();
    m.blocks_drawn = count(j.at("blocks_drawn"), "blocks_drawn", k64);
    m.seconds = j.at("seconds").get<double>();
    m.cpu_seconds = j.at("cpu_seconds").get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw bad(e.what());
  }
  if (m.count == 0 || m.index >= m.count) throw bad("shard " + std::to_string(m.index) + " of " + std::to_string(m.count));
  if (!std::is_sorted(m.streets.begin(), m.streets.end()) ||
      std::adjacent_find(m.streets.begin(), m.streets.end()) != m.streets.end())
    throw bad("streets are not ascending and distinct");
  return m;
}

std::string planDigest(const std::vector<std::vector<uint32_t>>& plan) {
  std::string bytes;
  for (size_t k = 0; k < plan.size(); ++k) {
    bytes += "shard " + std::to_string(k) + ":";
    for (uint32_t h : plan[k]) bytes += " " + std::to_string(h);
    bytes += "\n";
  }
  return sha256Hex(bytes);
}

}  // namespace blvd::bake
