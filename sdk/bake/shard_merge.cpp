// `blvd pack merge`: shards of one bake into its package, byte for byte what
// a single bake writes (shard.h).
#include <algorithm>
#include <chrono>
#include <map>

#include "bake/bake.h"
#include "bake/pool_sizing.h"
#include "bake/shard.h"
#include "core/status.h"
#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/street_graph.h"
#include "package/reader.h"
#include "package/writer.h"

namespace blvd::bake {
namespace {

struct OpenShard {
  std::string path;
  package::PackageReader reader;
  ShardManifest m;
};

core::Error refuse(const std::string& what) { return core::Error(core::Status::InvalidArg, what); }

// Opens a shard, checking every checksum of it, and reads its manifest.
OpenShard openShard(const std::string& path) {
  OpenShard s;
  s.path = path;
  s.reader = package::PackageReader::openOrThrow(path);
  std::string err;
  if (s.reader.verify(err) != core::Status::Ok) throw core::Error(core::Status::Corrupt, err);
  if (!s.reader.hasSection(package::kSectionShard))
    throw refuse(path + ": not a bake shard (no SHRD section; a package is merged from the shards `blvd bake --shard` writes)");
  const package::Span j = s.reader.section(package::kSectionShard);
  s.m = parseManifest(std::string(reinterpret_cast<const char*>(j.data), j.size), path);
  return s;
}

bool sameBytes(const package::Span& a, const package::Span& b) {
  return a.size == b.size && std::equal(a.data, a.data + a.size, b.data);
}

// The sections and blobs every shard computes alike; a bake with --dem has
// the optional ones too (the ground under the streets, the terrain's tiles).
constexpr uint32_t kShared[] = {package::kSectionGraph, package::kSectionCells, package::kSectionSpatialIndex,
                                package::kSectionBlocks, package::kSectionMeta};
constexpr uint32_t kSharedOptional[] = {package::kSectionElevation, package::kSectionTerrain};

// `s` belongs with `first`: the same bake, split the same way.
void checkSameBake(const OpenShard& first, const OpenShard& s) {
  const ShardManifest &a = first.m, &b = s.m;
  const std::string vs = " than " + first.path + " (";
  if (b.count != a.count)
    throw refuse(s.path + ": shard of " + std::to_string(b.count) + " shards, " + first.path + " of " + std::to_string(a.count));
  if (b.input_sha256 != a.input_sha256)
    throw refuse(s.path + ": baked from other input bytes (" + b.input_name + ", sha256 " + b.input_sha256.substr(0, 12) +
                 ")" + vs + a.input_name + ", sha256 " + a.input_sha256.substr(0, 12) + ")");
  if (b.options_sha256 != a.options_sha256) throw refuse(s.path + ": baked with other options" + vs + "options sha256 " +
                                                         a.options_sha256.substr(0, 12) + ", this one " + b.options_sha256.substr(0, 12) + ")");
  if (b.generator != a.generator) throw refuse(s.path + ": baked by " + b.generator + vs + a.generator + ")");
  if (b.plan_sha256 != a.plan_sha256 || b.block_blobs != a.block_blobs)
    throw refuse(s.path + ": its shard plan differs from " + first.path + "'s");
  for (uint32_t tag : kSharedOptional)
    if (s.reader.hasSection(tag) != first.reader.hasSection(tag))
      throw refuse(s.path + (s.reader.hasSection(tag) ? " has" : " lacks") + " the " + package::tagToString(tag) +
                   " section that " + first.path + (s.reader.hasSection(tag) ? " lacks" : " has") +
                   " (baked with --dem and without)");
  for (uint32_t tag : kShared)
    if (!sameBytes(s.reader.section(tag), first.reader.section(tag)))
      throw refuse(s.path + ": its " + package::tagToString(tag) + " section differs from " + first.path + "'s");
  for (uint32_t tag : kSharedOptional)
    if (first.reader.hasSection(tag) && !sameBytes(s.reader.section(tag), first.reader.section(tag)))
      throw refuse(s.path + ": its " + package::tagToString(tag) + " section differs from " + first.path + "'s");
  for (uint32_t i = 0; i < a.block_blobs; ++i)
    if (i >= s.reader.blobCount() || s.reader.blobInfo(i).crc != first.reader.blobInfo(i).crc ||
        s.reader.blobInfo(i).size != first.reader.blobInfo(i).size)
      throw refuse(s.path + ": block blob " + std::to_string(i) + " differs from " + first.path + "'s");
}

// Orders the shards by index and checks that they are shards 0..N-1 of one
// bake, each street in exactly one; returns each street's shard.
std::map<uint32_t, uint32_t> checkShards(std::vector<OpenShard>& shards) {
  if (shards.empty()) throw refuse("pack merge: no shards given");
  std::sort(shards.begin(), shards.end(), [](const OpenShard& a, const OpenShard& b) { return a.m.index < b.m.index; });
  for (const OpenShard& s : shards) checkSameBake(shards.front(), s);
  for (size_t k = 1; k < shards.size(); ++k)
    if (shards[k].m.index == shards[k - 1].m.index)
      throw refuse(shards[k - 1].path + " and " + shards[k].path + " are both shard " + std::to_string(shards[k].m.index));
  const uint32_t n = shards.front().m.count;
  for (uint32_t k = 0; k < n; ++k)
    if (k >= shards.size() || shards[k].m.index != k)
      throw refuse("pack merge: shard " + std::to_string(k) + " of " + std::to_string(n) + " is missing");
  std::map<uint32_t, uint32_t> owner;
  for (uint32_t k = 0; k < n; ++k)
    for (uint32_t h : shards[k].m.streets)
      if (!owner.emplace(h, k).second)
        throw refuse(shards[k].path + ": street " + std::to_string(h) + " is also in " + shards[owner[h]].path);
  if (owner.size() != shards.front().m.plan_streets)
    throw refuse("pack merge: the shards hold " + std::to_string(owner.size()) + " streets, the plan " +
                 std::to_string(shards.front().m.plan_streets));
  return owner;
}

std::vector<uint8_t> copyOf(const package::Span& s) { return std::vector<uint8_t>(s.data, s.data + s.size); }

// Blob i of a shard as it is stored (compressed or not), to be copied as is.
package::StoredBlob blobOf(const OpenShard& s, uint32_t i) {
  package::Span out;
  std::string err;
  if (s.reader.blob(i, out, err) != core::Status::Ok) throw core::Error(core::Status::Corrupt, err);
  const package::BlobInfo& info = s.reader.blobInfo(i);
  return package::StoredBlob{copyOf(out), info.flags, info.contents_size};
}

// A shard's cell tables, as its PVSA and IMPO sections hold them.
graph::CellTables tablesOf(const OpenShard& s, const graph::StreetGraph& g, uint32_t blocks) {
  graph::CellTables t;
  if (!s.reader.hasSection(package::kSectionVisibility)) return t;
  const package::Span v = s.reader.section(package::kSectionVisibility);
  const package::Span i = s.reader.section(package::kSectionImpostors);
  std::vector<float> lengths(g.halfedges.size());
  for (size_t h = 0; h < lengths.size(); ++h) lengths[h] = g.halfedges[h].length;
  graph::parseVisibility(v.data, v.size, v.offset, uint32_t(g.halfedges.size()), blocks, t);
  graph::parseImpostors(i.data, i.size, i.offset, lengths, blocks, s.reader.blobCount(), t);
  return t;
}

// Cell h's impostor layers from its shard's tables into `out`, their blobs
// added to `w` in the order the shard committed them (its blob order), which
// is the order a single bake commits them.
void takeCell(uint32_t h, const OpenShard& s, graph::CellTables& from, package::PackageWriter& w,
              graph::CellTables& out) {
  out.visibility[h] = std::move(from.visibility[h]);
  graph::CellImpostors& ci = from.impostors[h];
  std::vector<graph::ImpostorLayer*> layers;
  for (auto& l : ci.layered) layers.push_back(&l);
  for (auto& l : ci.single) layers.push_back(&l);
  std::sort(layers.begin(), layers.end(), [](auto* a, auto* b) { return a->blob < b->blob; });
  for (graph::ImpostorLayer* l : layers) l->blob = w.addStoredBlob(blobOf(s, l->blob));
  out.impostors[h] = std::move(ci);
}

}  // namespace

MergeSummary mergeShards(const std::vector<std::string>& paths, const std::string& out) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<OpenShard> shards;
  for (const std::string& p : paths) shards.push_back(openShard(p));
  const std::map<uint32_t, uint32_t> owner = checkShards(shards);
  const OpenShard& first = shards.front();

  graph::StreetGraph g;
  const package::Span gs = first.reader.section(package::kSectionGraph), cs = first.reader.section(package::kSectionCells);
  graph::parseGraph(gs.data, gs.size, gs.offset, g);
  graph::parseCells(cs.data, cs.size, cs.offset, g);
  std::vector<graph::BlockRecord> blocks;
  const package::Span bs = first.reader.section(package::kSectionBlocks);
  graph::parseBlocks(bs.data, bs.size, bs.offset, first.reader.blobCount(), blocks);

  package::PackageWriter w;
  for (uint32_t i = 0; i < first.m.block_blobs; ++i) w.addStoredBlob(blobOf(first, i));
  std::vector<graph::CellTables> from;
  for (const OpenShard& s : shards) from.push_back(tablesOf(s, g, uint32_t(blocks.size())));
  graph::CellTables merged;
  if (!from.front().visibility.empty()) {
    merged = from.front();  // the display fields; every cell is taken from its shard below
    const size_t H = g.halfedges.size();
    merged.visibility.assign(H, {});
    merged.impostors.assign(H, {});
    for (uint32_t h = 0; h < H; ++h) {
      const auto it = owner.find(std::min(h, g.halfedges[h].twin));
      if (it != owner.end()) takeCell(h, shards[it->second], from[it->second], w, merged);
    }
  }
  const package::PackageHeader& fh = first.reader.header();
  package::PackageHeader hdr;  // the city's fields; the pool sizing is the merged package's
  hdr.origin_lat = fh.origin_lat, hdr.origin_lon = fh.origin_lon, hdr.origin_h = fh.origin_h;
  std::copy_n(fh.bounds_min, 2, hdr.bounds_min), std::copy_n(fh.bounds_max, 2, hdr.bounds_max);
  hdr.junction_count = fh.junction_count, hdr.cell_count = fh.cell_count;
  hdr.block_count = fh.block_count, hdr.building_count = fh.building_count;
  hdr.triangle_count = fh.triangle_count, hdr.source_bytes = fh.source_bytes;
  fillPoolSizing(g, blocks, merged, [&](uint32_t i) { return uint64_t{w.blob(i).size()}; }, hdr);
  w.setHeader(hdr);
  const std::string meta = metaWithBlobCount(copyOf(first.reader.section(package::kSectionMeta)), w.blobCount());
  addPackageSections(w,
                     {copyOf(gs), copyOf(cs), copyOf(first.reader.section(package::kSectionSpatialIndex)),
                      copyOf(bs), std::vector<uint8_t>(meta.begin(), meta.end())},
                     merged);
  for (uint32_t tag : kSharedOptional)  // after the rest, as a single bake adds them
    if (first.reader.hasSection(tag)) w.addSection(tag, copyOf(first.reader.section(tag)));
  w.write(out);

  MergeSummary sum;
  double slowest = 0;
  for (size_t k = 0; k < shards.size(); ++k) {
    MergeShardLine line{shards[k].path, shards[k].m, shards[k].reader.fileSize(), 0};
    if (!from[k].impostors.empty())
      for (uint32_t h : line.manifest.streets)
        for (uint32_t c : {h, g.halfedges[h].twin})
          line.cells += !merged.impostors[c].layered.empty() || !merged.impostors[c].single.empty();
    sum.cpu_seconds += line.manifest.cpu_seconds;
    slowest = std::max(slowest, line.manifest.seconds);
    sum.imbalance += line.manifest.seconds;
    sum.shards.push_back(std::move(line));
  }
  sum.imbalance = sum.imbalance > 0 ? slowest / (sum.imbalance / double(shards.size())) : 1.0;
  sum.package_bytes = w.fileBytes();
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sum;
}

}  // namespace blvd::bake
