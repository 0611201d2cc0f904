// `blvd bench memory PKG_1X PKG_4X`: drives the same route on a package and on
// a larger one (Monaco and Monaco tiled 2×2 by `blvd bake --tile 2x2`) in two
// fresh child processes of this binary, one after the other, and compares
// their peak resident memory (VmHWM) and the heap allocations each frame makes
// on the render thread after warm-up (resident memory independent of
// city size, zero allocations per frame).
//
// The child, `blvd bench memory-drive`, prints one JSON line; it is a
// subcommand of its own so that each package gets a clean process and a peak
// of its own.
#include <malloc.h>
#include <unistd.h>

#include <cctype>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "cli/bench_util.h"
#include "cli/commands.h"
#include "cli/drive_child.h"
#include "cli/malloc_probe.h"
#include "cli/route.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {


long statusKiB(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, n, key) == 0) return std::strtol(line.c_str() + n, nullptr, 10);
  return -1;
}

std::vector<uint32_t> parseCells(const std::string& s) {
  std::vector<uint32_t> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(static_cast<uint32_t>(std::stoul(item)));
  return out;
}

// Frame time and triangles of every pose in `mode`, each pose resident first,
// one untimed frame, then `repeat` timed ones (their median is the pose's).
nlohmann::json timeFrames(blvd_runtime* rt, const std::vector<Pose>& poses, blvd_render_mode mode, int repeat) {
  check(blvd_set_render_mode(rt, mode, 0.f), rt, "mode");
  std::vector<double> ms, tris;
  for (const Pose& p : poses) {
    check(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), rt, "pose");
    check(blvd_wait_resident(rt, 60000), rt, "wait");
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    check(blvd_render(rt, &fs), rt, "render");
    std::vector<double> pose_ms;
    for (int r = 0; r < repeat; ++r) {
      check(blvd_render(rt, &fs), rt, "render");
      pose_ms.push_back(fs.frame_ms);
    }
    ms.push_back(pct(pose_ms, 50));
    tris.push_back(double(fs.triangles));
  }
  return {{"frame_ms_p50", pct(ms, 50)}, {"frame_ms_p95", pct(ms, 95)}, {"triangles_p50", pct(tris, 50)},
          {"poses", poses.size()}};
}

// Resident KiB of the mappings of `path` (/proc/self/smaps): the package's
// pages the process holds.
long mappingRssKiB(const std::string& path) {
  char real[4096];
  if (!::realpath(path.c_str(), real)) return -1;
  std::ifstream f("/proc/self/smaps");
  std::string line;
  bool in = false;
  long kib = 0;
  while (std::getline(f, line)) {
    if (!line.empty() && std::isxdigit(static_cast<unsigned char>(line[0])) && line.find('-') != std::string::npos &&
        line.find(' ') < line.size()) {
      in = line.size() >= std::strlen(real) && line.compare(line.size() - std::strlen(real), std::string::npos, real) == 0;
      continue;
    }
    if (in && line.rfind("Rss:", 0) == 0) kib += std::atol(line.c_str() + 4);
  }
  return kib;
}

// The child: one package, one route, `laps` laps; lap 1 is the warm-up.
int runDrive(const MemoryOpts& o) {
  // glibc raises its mmap threshold each time a large mmapped block is freed
  // (up to 32 MiB); bigger tables at open then push later driver buffers into
  // the main heap, where they fragment it. A host with a memory budget pins
  // the threshold; so does this bench, so that the peak measures blvd.
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  int w = 0, h = 0;
  if (std::sscanf(o.size.c_str(), "%dx%d", &w, &h) != 2) throw core::Error(core::Status::InvalidArg, "--size");
  const std::vector<uint32_t> route = parseCells(o.cells);
  std::vector<Pose> poses;
  bool impostors = false;
  {
    // Paged, as the runtime opens it: the poses need only the route's cells,
    // and the peak RSS measured below must not hold a whole graph the runtime does not.
    stream::City city;
    std::string err;
    const core::Status st = city.open(o.pkg_1x, err, stream::City::Tables::All, stream::City::GraphTables::Paged);
    if (st != core::Status::Ok) throw core::Error(st, err);
    for (uint32_t c : route)
      if (c >= city.streets().cellCount()) throw core::Error(core::Status::InvalidArg, "route cell out of range");
    poses = samplePoses(city.streets(), route, o.step);
    impostors = city.hasImpostors();
  }
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = o.pkg_1x.c_str();
  desc.width = uint32_t(w);
  desc.height = uint32_t(h);
  desc.mode = impostors ? BLVD_MODE_BLVD : BLVD_MODE_LOCAL;  // never the all-blocks reference modes
  blvd_runtime* rt = nullptr;
  check(blvd_runtime_create(&desc, &rt), nullptr, "create runtime");
  std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)> guard(rt, blvd_runtime_destroy);
  check(blvd_set_route(rt, route.data(), route.size()), rt, "route");
  long blvd_max = 0, driver_max = 0;
  size_t frames = 0, waited = 0;
  for (int lap = 0; lap < o.laps; ++lap)
    for (const Pose& p : poses) {
      check(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), rt, "pose");
      blvd_frame_stats fs{};
      fs.struct_size = sizeof fs;
      probe::ThreadMallocCounter counter;
      check(blvd_render(rt, &fs), rt, "render");
      if (fs.flags & BLVD_FRAME_DEGRADED) {
        ++waited;
        check(blvd_wait_resident(rt, 60000), rt, "wait");
        check(blvd_render(rt, &fs), rt, "render");
      }
      if (lap > 0) {  // after warm-up
        blvd_max = std::max(blvd_max, counter.count());
        driver_max = std::max(driver_max, counter.driverCount());
        ++frames;
      }
    }
  blvd_stats s{};
  s.struct_size = sizeof s;
  check(blvd_runtime_stats(rt, &s), rt, "stats");
  nlohmann::json j;
  j["rss_peak"] = statusKiB("VmHWM:") * 1024;  // before the full model's frames, which hold every block
  if (o.frame_repeat > 0) {
    j["blvd"] = timeFrames(rt, poses, desc.mode, o.frame_repeat);
    j["full"] = timeFrames(rt, poses, BLVD_MODE_FULL, o.frame_repeat);
  }
  j["rss_anon_end"] = statusKiB("RssAnon:") * 1024;  // heap and GL buffers
  j["rss_file_end"] = statusKiB("RssFile:") * 1024;  // mapped libraries and package pages
  j["rss_package_end"] = mappingRssKiB(o.pkg_1x) * 1024;  // of which the package's
  j["allocs_per_frame_max"] = blvd_max;
  j["driver_allocs_per_frame_max"] = driver_max;
  j["frames"] = frames;
  j["frames_waited"] = waited;
  j["loads"] = s.loads;
  j["table_bytes"] = s.table_bytes;
  j["tracking_bytes"] = s.tracking_bytes;
  j["gpu_high_water"] = s.gpu.high_water_bytes;
  j["malloc_probe"] = probe::ThreadMallocCounter::available();
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

int runMemory(const MemoryOpts& o) {
  const unsigned n = parseAutoRoute(o.route);
  stream::City a, b;
  std::string err;
  core::Status st = a.open(o.pkg_1x, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  st = b.open(o.pkg_4x, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  const std::vector<uint32_t> route = graph::seededRoute(a.graph(), {n, o.seed});
  checkSameRoute(a, b, route);
  const std::string cells = cellList(route), exe = selfExe();
  std::fprintf(stderr, "bench memory: %zu cells, %d laps, on %s then %s\n", route.size(), o.laps, o.pkg_1x.c_str(),
               o.pkg_4x.c_str());
  const nlohmann::json r1 = driveChild(exe, o.pkg_1x, cells, o), r4 = driveChild(exe, o.pkg_4x, cells, o);
  nlohmann::json j;
  j["route_cells"] = route.size();
  j["route"] = route;
  j["rss_peak_1x"] = r1["rss_peak"];
  j["rss_peak_4x"] = r4["rss_peak"];
  const double p1 = r1["rss_peak"].get<double>(), p4 = r4["rss_peak"].get<double>();
  j["rss_diff_pct"] = 100.0 * (p4 - p1) / p1;
  j["allocs_per_frame_max"] = std::max(r1["allocs_per_frame_max"].get<long>(), r4["allocs_per_frame_max"].get<long>());
  j["driver_allocs_per_frame_max"] =
      std::max(r1["driver_allocs_per_frame_max"].get<long>(), r4["driver_allocs_per_frame_max"].get<long>());
  j["table_bytes_1x"] = r1["table_bytes"];
  j["table_bytes_4x"] = r4["table_bytes"];
  j["runs"] = {{"1x", r1}, {"4x", r4}};
  j["pass"] = std::fabs(j["rss_diff_pct"].get<double>()) <= o.max_rss_diff_pct && j["allocs_per_frame_max"] == 0 &&
              r1["malloc_probe"].get<bool>();
  const std::string text = j.dump(2);
  std::printf("%s\n", text.c_str());
  writeText(o.json_path, text);
  return 0;
}

}  // namespace

// The same cells, with the same geometry, must exist in the larger package.
void checkSameRoute(const stream::City& a, const stream::City& b, const std::vector<uint32_t>& route) {
  for (uint32_t c : route) {
    if (c >= b.graph().cellCount())
      throw core::Error(core::Status::InvalidArg, "the larger package has no cell " + std::to_string(c));
    const auto &ea = a.graph().halfedges[c], &eb = b.graph().halfedges[c];
    const glm::dvec2 pa = a.graph().points[ea.pts_begin], pb = b.graph().points[eb.pts_begin];
    if (std::fabs(ea.length - eb.length) > 0.01 || glm::length(pa - pb) > 0.01)
      throw core::Error(core::Status::InvalidArg,
                        "cell " + std::to_string(c) + " differs between the packages: the larger one must keep the "
                        "smaller one's cells first (blvd bake --tile keeps tile 0 as the original)");
  }
}

nlohmann::json driveChild(const std::string& exe, const std::string& pkg, const std::string& cells, const MemoryOpts& o) {
  char step[32];
  std::snprintf(step, sizeof step, "%g", o.step);
  const std::string cmd = "'" + exe + "' bench memory-drive '" + pkg + "' --cells " + cells + " --step " + step +
                          " --size " + o.size + " --laps " + std::to_string(o.laps) +
                          " --frame-repeat " + std::to_string(o.frame_repeat);
  FILE* f = ::popen(cmd.c_str(), "r");
  if (!f) throw core::Error(core::Status::Io, "cannot run " + cmd);
  std::string out;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, f)) out.append(buf, n);
  const int rc = ::pclose(f);
  if (rc != 0) throw core::Error(core::Status::Internal, "child failed (" + std::to_string(rc) + "): " + cmd);
  // The JSON is the child's last line (its objects nest: not the last '{').
  const size_t end = out.find_last_not_of("\n");
  const size_t line = end == std::string::npos ? std::string::npos : out.rfind('\n', end);
  const std::string last = end == std::string::npos ? "" : out.substr(line == std::string::npos ? 0 : line + 1);
  if (last.empty() || last[0] != '{') throw core::Error(core::Status::Internal, "child printed no JSON: " + out);
  return nlohmann::json::parse(last);
}

std::string selfExe() {
  char exe[4096];
  const ssize_t len = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (len <= 0) throw core::Error(core::Status::Io, "cannot find this executable (/proc/self/exe)");
  exe[len] = 0;
  return exe;
}

std::string cellList(const std::vector<uint32_t>& route) {
  std::string cells;
  for (uint32_t c : route) cells += (cells.empty() ? "" : ",") + std::to_string(c);
  return cells;
}


void addBenchMemory(CLI::App& bench, Runner& run) {
  auto o = std::make_shared<MemoryOpts>();
  auto* m = bench.add_subcommand("memory", "peak RSS and render-thread allocations on a package and a 4x one");
  m->add_option("pkg_1x", o->pkg_1x)->required()->check(CLI::ExistingFile);
  m->add_option("pkg_4x", o->pkg_4x)->required()->check(CLI::ExistingFile);
  m->add_option("--route", o->route, "auto:N cells of the first package, driven on both")->capture_default_str();
  m->add_option("--seed", o->seed)->capture_default_str();
  m->add_option("--step", o->step, "metres between frames")->capture_default_str();
  m->add_option("--laps", o->laps, "laps of the route; the first warms up")->capture_default_str()->check(CLI::Range(2, 100));
  m->add_option("--size", o->size)->capture_default_str();
  m->add_option("--json", o->json_path, "write the JSON here too");
  m->callback([o, &run] { run = [o] { return runMemory(*o); }; });

  auto d = std::make_shared<MemoryOpts>();
  auto* c = bench.add_subcommand("memory-drive", "");  // the child of `bench memory`; hidden
  c->group("");
  c->add_option("package", d->pkg_1x)->required();
  c->add_option("--cells", d->cells)->required();
  c->add_option("--step", d->step);
  c->add_option("--laps", d->laps);
  c->add_option("--size", d->size);
  c->add_option("--frame-repeat", d->frame_repeat);
  c->callback([d, &run] { run = [d] { return runDrive(*d); }; });
}

}  // namespace blvd::cli
