// `blvd pack merge SHARD... -o OUT`: the shards of a bake into its package.
#include <cstdio>

#include "bake/shard.h"
#include "cli/commands.h"

namespace blvd::cli {
namespace {

int merge(const std::vector<std::string>& shards, const std::string& out) {
  const bake::MergeSummary s = bake::mergeShards(shards, out);
  for (const bake::MergeShardLine& l : s.shards)
    std::printf("  shard %u/%u %s: %zu streets, %u cells with impostors, %.1f s (%.1f s CPU), %llu bytes\n",
                l.manifest.index, l.manifest.count, l.path.c_str(), l.manifest.streets.size(), l.cells,
                l.manifest.seconds, l.manifest.cpu_seconds, static_cast<unsigned long long>(l.bytes));
  std::printf("merged %zu shards -> %s in %.2f s: %llu bytes; imbalance %.2f (slowest shard / mean), %.1f CPU s in all\n",
              s.shards.size(), out.c_str(), s.seconds, static_cast<unsigned long long>(s.package_bytes), s.imbalance,
              s.cpu_seconds);
  return 0;
}

}  // namespace

void addPackMerge(CLI::App& pack, Runner& run) {
  struct Opts {
    std::vector<std::string> shards;
    std::string out;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = pack.add_subcommand(
      "merge", "join the shard files of `blvd bake --shard` into the package a single bake writes (byte for byte)");
  cmd->add_option("shards", o->shards, "every shard file of the bake, in any order")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "package to write (.blvd)")->required();
  cmd->callback([&run, o] { run = [o] { return merge(o->shards, o->out); }; });
}

}  // namespace blvd::cli
