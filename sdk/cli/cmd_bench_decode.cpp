// `blvd bench decode PKG [PKG ...]`: what the loader's decode of each mesh
// costs, per package, side by side in one run (decision 0008 §12): every
// block level and every impostor layer is decoded (GLB, Draco, the image) and
// prepared into the renderer's staging layout exactly as the loader does, the
// packages taking turns mesh kind by mesh kind, and timed by the thread's CPU
// clock (what the decode takes from the other threads on its core). Reported:
// per package and kind the meshes, p50 / p90 / max and the total in ms, a
// cell's impostors together (p50 / max: what one cell load decodes), the
// package bytes, the memory plan at the default descriptor (GPU bytes of one
// cell slot, all of the GPU and CPU pools), and each package's total against
// the first's. With ETC2 atlases (blvd_runtime_desc.impostor_texture) the
// loader also encodes each image's atlas levels: `impostors_etc2` and
// `cell_impostors_etc2` add that encoding, timed right after each decode, and
// `memory_etc2` is the plan with that descriptor.
#include <sys/stat.h>
#include <time.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/memory_plan.h"
#include "cli/bench_util.h"
#include "cli/commands.h"
#include "render/atlas_etc2.h"
#include "render/prepared_mesh.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct DecodeOpts {
  std::vector<std::string> packages;
  std::string json_path;
  int rounds = 1;  // times every mesh is decoded (the minimum is kept)
};

double threadCpuMs() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

struct Kind {
  std::vector<double> ms;  // one per mesh
};

struct Package {
  stream::City city;
  Kind blocks, impostors, impostors_etc2;
  Kind cell_impostors, cell_impostors_etc2;  // one entry per cell with impostors: its layers' sum
  uint64_t bytes = 0;
  runtime::MemoryPlan plan, plan_etc2;  // at the default descriptor, and with ETC2 atlases
};

// Thread CPU ms of one mesh (the least of `rounds` each): decoding and
// staging it, and (`etc2_ms`, when not null) then encoding its image's ETC2
// atlas levels as the loader does for ETC2 slots.
template <typename Decode>
double timeMesh(Decode&& decode, geo::MeshData& scratch, render::StagingArena& arena, int rounds,
                double* etc2_ms = nullptr) {
  double best = 1e300, best_etc2 = 1e300;
  for (int r = 0; r < rounds; ++r) {
    std::string err;
    arena.reset();
    const double t0 = threadCpuMs();
    core::Status st = decode(scratch, err);
    render::PreparedMesh m;
    if (st == core::Status::Ok && !scratch.empty() && !render::prepareMesh(scratch, arena, m, err))
      st = core::Status::Internal;
    const double t1 = threadCpuMs();
    if (st == core::Status::Ok && etc2_ms && m.rgba && !render::encodeAtlasEtc2(m, arena, err))
      st = core::Status::Internal;
    if (st != core::Status::Ok) throw core::Error(st, err);
    best = std::min(best, t1 - t0);
    best_etc2 = std::min(best_etc2, threadCpuMs() - t1);
  }
  if (etc2_ms) *etc2_ms = best_etc2;
  return best;
}

nlohmann::json summary(const Kind& k) {
  double sum = 0;
  for (double x : k.ms) sum += x;
  return {{"meshes", k.ms.size()},   {"ms_p50", pct(k.ms, 50)}, {"ms_p90", pct(k.ms, 90)},
          {"ms_max", pct(k.ms, 100)}, {"ms_total", sum}};
}

nlohmann::json memoryJson(const runtime::MemoryPlan& m) {
  return {{"resident_cells", m.resident_cells},
          {"slab_bytes", render::slabGpuBytes(m.slab)},
          {"slab_atlas_width", m.slab.atlas_width},
          {"slab_atlas_height", m.slab.atlas_height},
          {"gpu_bytes", m.gpu_bytes},
          {"cpu_bytes", m.cpu_bytes}};
}

int runDecode(const DecodeOpts& o) {
  std::vector<std::unique_ptr<Package>> pkgs;
  uint64_t arena_size = 0;  // the loader's staging arena for the largest of the packages
  for (const std::string& path : o.packages) {
    auto p = std::make_unique<Package>();
    std::string err;
    const core::Status st = p->city.open(path, err);
    if (st != core::Status::Ok) throw core::Error(st, err);
    struct stat sb{};
    if (::stat(path.c_str(), &sb) == 0) p->bytes = uint64_t(sb.st_size);
    blvd_runtime_desc d{};
    d.struct_size = sizeof d;
    d = blvd_runtime_desc_defaults(&d);
    p->plan = runtime::planMemory(d, p->city);
    d.impostor_texture = BLVD_TEXTURE_ETC2;
    p->plan_etc2 = runtime::planMemory(d, p->city);
    arena_size = std::max(arena_size, p->plan_etc2.staging_arena_bytes);
    pkgs.push_back(std::move(p));
  }
  // One arena as the loader carves it (a whole cell's meshes fit), reset per mesh.
  std::vector<uint8_t> arena_bytes(arena_size);
  render::StagingArena arena{arena_bytes.data(), arena_bytes.size(), 0};
  geo::MeshData scratch;
  std::fprintf(stderr, "bench decode: %zu packages, every block level and impostor layer ...\n", pkgs.size());
  // Blocks: each package's block b, level k in turn, as the loader decodes
  // them (one open per blob, its CRC and JSON counted with level 0).
  size_t blocks = 0;
  for (const auto& p : pkgs) blocks = std::max(blocks, p->city.blocks().size());
  stream::City::BlockBlob blob;
  for (uint32_t b = 0; b < blocks; ++b)
    for (const auto& p : pkgs) {
      if (b >= p->city.blocks().size() || p->city.blocks()[b].blob == 0xffffffffu) continue;
      for (uint32_t k = 0; k < p->city.blocks()[b].lod_count; ++k)
        p->blocks.ms.push_back(timeMesh(
            [&](geo::MeshData& m, std::string& e) {
              if (k == 0)
                if (const core::Status st = p->city.openBlock(b, blob, e); st != core::Status::Ok) return st;
              return p->city.decodeBlockLevel(blob, k, m, e);
            },
            scratch, arena, o.rounds));
      blob.close();
    }
  size_t cells = 0;
  for (const auto& p : pkgs) cells = std::max(cells, p->city.cellTables().impostors.size());
  for (size_t c = 0; c < cells; ++c)
    for (const auto& p : pkgs) {
      if (c >= p->city.cellTables().impostors.size()) continue;
      const graph::CellImpostors& ci = p->city.cellTables().impostors[c];
      double cell_ms = 0, cell_etc2_ms = 0;
      for (const auto* list : {&ci.layered, &ci.single})
        for (const graph::ImpostorLayer& layer : *list) {
          auto decode = [&](geo::MeshData& m, std::string& e) { return p->city.decodeImpostor(layer, m, e); };
          double encode_ms = 0;
          p->impostors.ms.push_back(timeMesh(decode, scratch, arena, o.rounds, &encode_ms));
          p->impostors_etc2.ms.push_back(p->impostors.ms.back() + encode_ms);
          cell_ms += p->impostors.ms.back();
          cell_etc2_ms += p->impostors_etc2.ms.back();
        }
      if (!ci.layered.empty() || !ci.single.empty()) {
        p->cell_impostors.ms.push_back(cell_ms);
        p->cell_impostors_etc2.ms.push_back(cell_etc2_ms);
      }
    }
  nlohmann::json out = nlohmann::json::array();
  double first_total = 0;
  for (size_t i = 0; i < pkgs.size(); ++i) {
    const Package& p = *pkgs[i];
    nlohmann::json j = {{"package", o.packages[i]}, {"bytes", p.bytes}, {"blocks", summary(p.blocks)},
                        {"impostors", summary(p.impostors)}, {"cell_impostors", summary(p.cell_impostors)},
                        {"impostors_etc2", summary(p.impostors_etc2)},
                        {"cell_impostors_etc2", summary(p.cell_impostors_etc2)},
                        {"memory", memoryJson(p.plan)}, {"memory_etc2", memoryJson(p.plan_etc2)}};
    const double total = j["blocks"]["ms_total"].get<double>() + j["impostors"]["ms_total"].get<double>();
    if (i == 0) first_total = total;
    j["ms_total"] = total;
    j["ms_total_vs_first"] = first_total > 0 ? total / first_total : NAN;
    j["bytes_vs_first"] = pkgs[0]->bytes ? double(p.bytes) / double(pkgs[0]->bytes) : NAN;
    out.push_back(j);
  }
  const std::string text = out.dump(2);
  std::printf("%s\n", text.c_str());
  if (!o.json_path.empty()) {
    std::ofstream f(o.json_path);
    f << text << "\n";
    if (!f) throw core::Error(core::Status::Io, "cannot write " + o.json_path);
  }
  return 0;
}

}  // namespace

void addBenchDecode(CLI::App& bench, Runner& run) {
  auto o = std::make_shared<DecodeOpts>();
  auto* d = bench.add_subcommand("decode", "CPU cost of decoding every mesh of one or more packages, side by side");
  d->add_option("packages", o->packages, "packages (the first is the reference of the ratios)")
      ->required()
      ->check(CLI::ExistingFile);
  d->add_option("--rounds", o->rounds, "decodes per mesh (the least time is kept)")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  d->add_option("--json", o->json_path, "write the JSON here too");
  d->callback([o, &run] { run = [o] { return runDecode(*o); }; });
}

}  // namespace blvd::cli
