// `blvd view`: one frame at a pose, or a drive along a street path (frames +
// index.html). Goes through the public C API, like a host would.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include "blvd/blvd.h"
#include "cli/commands.h"
#include "cli/route.h"
#include "core/status.h"
#include "imaging/image.h"
#include "stream/city.h"

namespace blvd::cli {
namespace {

struct ViewOpts {
  std::string package, out, size = "800x480", backend = "auto", path, mode = "blvd";
  std::string items;  // one pose: also write its object-id buffer as a PNG
  std::string impostor_texture = "rgba8";  // blvd_runtime_desc.impostor_texture
  double lat = NAN, lon = NAN, heading = 0, pitch = 0, fov = 45, step = 8;
  uint64_t seed = 1;
  int repeat = 1;
  bool with_full = false;  // a drive also writes the full model's frame of each pose
};

void check(blvd_status st, blvd_runtime* rt, const char* what) {
  if (st != BLVD_OK)
    throw core::Error(static_cast<core::Status>(st), std::string(what) + ": " + blvd_last_error(rt));
}

}  // namespace

bool parseMode(const std::string& s, blvd_render_mode& mode, float& radius) {
  radius = 0;
  if (s == "blvd" || s == "layered") mode = BLVD_MODE_BLVD;
  else if (s == "full") mode = BLVD_MODE_FULL;
  else if (s == "local") mode = BLVD_MODE_LOCAL;
  else if (s == "single") mode = BLVD_MODE_SINGLE;
  else if (std::sscanf(s.c_str(), "radius:%f", &radius) == 1 && radius > 0) mode = BLVD_MODE_RADIUS;
  else return false;
  return true;
}

namespace {

blvd_backend parseBackendName(const std::string& s) {
  if (s == "auto") return BLVD_BACKEND_AUTO;
  if (s == "egl-surfaceless") return BLVD_BACKEND_EGL_SURFACELESS;
  if (s == "egl-device") return BLVD_BACKEND_EGL_DEVICE;
  if (s == "osmesa") return BLVD_BACKEND_OSMESA;
  throw core::Error(core::Status::InvalidArg, "unknown backend '" + s + "' (auto, egl-surfaceless, egl-device, osmesa)");
}

// The object ids of the frame just drawn as a PNG: RGB holds the 24-bit id
// (block + 1, or BLVD_ITEM_IMPOSTOR | layer + 1), alpha 0 where nothing is.
void writeItems(blvd_runtime* rt, int w, int h, const std::string& path, std::vector<uint8_t>& rgba) {
  std::vector<uint32_t> ids(size_t(w) * h);
  check(blvd_read_items(rt, ids.data(), ids.size()), rt, "read items");
  for (size_t i = 0; i < ids.size(); ++i) {
    uint8_t* p = &rgba[4 * i];
    p[0] = uint8_t(ids[i]), p[1] = uint8_t(ids[i] >> 8), p[2] = uint8_t(ids[i] >> 16), p[3] = ids[i] ? 255 : 0;
  }
  std::string err;
  if (!imaging::writePng(path, w, h, rgba.data(), err)) throw core::Error(core::Status::Io, err);
}

void writeFrame(blvd_runtime* rt, int w, int h, const std::string& path, std::vector<uint8_t>& rgba) {
  check(blvd_read_pixels(rt, rgba.data(), rgba.size()), rt, "read pixels");
  std::string err;
  if (!imaging::writePng(path, w, h, rgba.data(), err)) throw core::Error(core::Status::Io, err);
}

const char* fullName(char (&buf)[64], size_t i) {
  std::snprintf(buf, sizeof buf, "frame_%04zu_full.png", i);
  return buf;
}

// The full model's frame of the pose just drawn, then back to the drive's mode.
void writeFullFrame(blvd_runtime* rt, const blvd_runtime_desc& desc, int w, int h, const std::string& path,
                    std::vector<uint8_t>& rgba) {
  check(blvd_set_render_mode(rt, BLVD_MODE_FULL, 0.f), rt, "mode");
  check(blvd_wait_resident(rt, 60000), rt, "load the full model");
  check(blvd_render(rt, nullptr), rt, "render");
  writeFrame(rt, w, h, path, rgba);
  check(blvd_set_render_mode(rt, desc.mode, desc.radius_m), rt, "mode");
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int run(const ViewOpts& o) {
  int w = 0, h = 0;
  if (std::sscanf(o.size.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
    throw core::Error(core::Status::InvalidArg, "--size must be WIDTHxHEIGHT, e.g. 800x480");
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = o.package.c_str();
  desc.width = static_cast<uint32_t>(w);
  desc.height = static_cast<uint32_t>(h);
  desc.fov_y_deg = static_cast<float>(o.fov);
  desc.backend = parseBackendName(o.backend);
  desc.impostor_texture = o.impostor_texture == "etc2" ? BLVD_TEXTURE_ETC2 : BLVD_TEXTURE_RGBA8;
  if (!parseMode(o.mode, desc.mode, desc.radius_m))
    throw core::Error(core::Status::InvalidArg, "--mode must be full, local, radius:R, single, layered or blvd");
  blvd_runtime* rt = nullptr;
  check(blvd_runtime_create(&desc, &rt), nullptr, "create runtime");
  std::unique_ptr<blvd_runtime, void (*)(blvd_runtime*)> guard(rt, blvd_runtime_destroy);
  blvd_runtime_info info{};
  info.struct_size = sizeof info;
  check(blvd_runtime_get_info(rt, &info), rt, "info");
  std::fprintf(stderr, "blvd view: %s on %s (%s), %u blocks, %llu triangles\n", o.package.c_str(), info.backend,
               info.gl_renderer, info.block_count, static_cast<unsigned long long>(info.triangle_count));
  std::vector<uint8_t> rgba(static_cast<size_t>(w) * h * 4);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;

  if (o.path.empty()) {
    if (std::isnan(o.lat) || std::isnan(o.lon)) throw core::Error(core::Status::InvalidArg, "give --lat and --lon, or --path");
    check(blvd_set_pose_geo(rt, o.lat, o.lon, static_cast<float>(o.heading), static_cast<float>(o.pitch)), rt, "pose");
    check(blvd_wait_resident(rt, 60000), rt, "wait for the cell");
    // The first frame pays for shader compilation and first-touch uploads;
    // with --repeat N the median of frames 2..N+1 is reported.
    std::vector<double> ms;
    for (int i = 0; i <= (o.repeat > 1 ? o.repeat : 0); ++i) {
      check(blvd_render(rt, &fs), rt, "render");
      if (i > 0 || o.repeat <= 1) ms.push_back(fs.frame_ms);
    }
    writeFrame(rt, w, h, o.out, rgba);
    if (!o.items.empty()) writeItems(rt, w, h, o.items, rgba);
    blvd_stats st{};
    st.struct_size = sizeof st;
    check(blvd_runtime_stats(rt, &st), rt, "stats");
    std::printf("wrote %s (%s %.1f ms over %zu frames, %llu triangles, %u draw calls, cell %u, %u impostor layers, "
                "%u terrain tiles)\n",
                o.out.c_str(), ms.size() > 1 ? "median" : "frame", median(ms), ms.size(),
                static_cast<unsigned long long>(fs.triangles), fs.draw_calls, fs.cell, fs.impostor_layers,
                st.terrain_tiles);
    return 0;
  }

  // A drive: --path auto:N picks N connected cells from --seed.
  unsigned n = 0;
  if (std::sscanf(o.path.c_str(), "auto:%u", &n) != 1 || n == 0 || n > 10000)
    throw core::Error(core::Status::InvalidArg, "--path must be auto:N (N cells)");
  stream::City city;
  std::string err;
  const core::Status st = city.open(o.package, err);
  if (st != core::Status::Ok) throw core::Error(st, err);
  const auto route = graph::seededRoute(city.graph(), {n, o.seed});
  const auto poses = samplePoses(city.streets(), route, o.step);
  ::mkdir(o.out.c_str(), 0755);
  std::vector<double> ms;
  std::ofstream html(o.out + "/index.html");
  html << "<!doctype html><meta charset=utf-8><title>blvd drive: " << o.package << "</title>\n"
       << "<style>body{font:14px sans-serif;background:#222;color:#ddd;margin:1em}figure{display:inline-block;"
          "margin:4px}img{width:400px;display:block}figcaption{font-size:12px}</style>\n"
       << "<h1>blvd drive</h1><p>" << o.package << " &middot; " << route.size() << " cells, " << poses.size()
       << " frames, " << w << "&times;" << h << " on " << info.backend << " (" << info.gl_renderer
       << ")</p>\n<p>Map data &copy; OpenStreetMap contributors (ODbL)</p>\n";
  if (o.with_full)
    html << "<p><button onclick=\"flipAll()\">show the full model / blvd</button>; click a frame to flip it alone:"
            " an orange outline marks the full model</p>\n"
            "<script>function flip(i){const f=i.getAttribute('src')==i.dataset.blvd;i.src=f?i.dataset.full:"
            "i.dataset.blvd;i.style.outline=f?'3px solid #e94':'none';}"
            "function flipAll(){document.querySelectorAll('img[data-full]').forEach(flip);}</script>\n";
  // The route lets residency prefetch exactly the cells ahead. A drive steps
  // --step metres a frame, far faster than a car, so a frame whose cell is
  // still loading is counted, then the cell is waited for and drawn again.
  check(blvd_set_route(rt, route.data(), route.size()), rt, "route");
  size_t degraded = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Pose& p = poses[i];
    check(blvd_set_pose_local(rt, p.x, p.y, static_cast<float>(p.heading_deg), static_cast<float>(o.pitch)), rt, "pose");
    check(blvd_render(rt, &fs), rt, "render");
    if (fs.flags & BLVD_FRAME_DEGRADED) {
      ++degraded;
      check(blvd_wait_resident(rt, 60000), rt, "wait for the cell");
      check(blvd_render(rt, &fs), rt, "render");
    }
    ms.push_back(fs.frame_ms);
    char name[64], full_name[64];
    std::snprintf(name, sizeof name, "frame_%04zu.png", i);
    writeFrame(rt, w, h, o.out + "/" + name, rgba);
    if (o.with_full) writeFullFrame(rt, desc, w, h, o.out + "/" + fullName(full_name, i), rgba);
    double lat = 0, lon = 0, alt = 0;
    city.frame().reverse({p.x, p.y, 0}, lat, lon, alt);
    char caption[256];
    std::snprintf(caption, sizeof caption,
                  "#%zu cell %u &middot; %.6f, %.6f heading %.0f&deg; &middot; %.1f ms, %llu triangles", i, p.cell,
                  lat, lon, p.heading_deg, fs.frame_ms, static_cast<unsigned long long>(fs.triangles));
    if (o.with_full)
      html << "<figure><img src=\"" << name << "\" data-blvd=\"" << name << "\" data-full=\"" << full_name
           << "\" onclick=\"flip(this)\" title=\"click: blvd / full model\"><figcaption>" << caption
           << "</figcaption></figure>\n";
    else
      html << "<figure><img src=\"" << name << "\"><figcaption>" << caption << "</figcaption></figure>\n";
    std::fprintf(stderr, "\r  frame %zu/%zu", i + 1, poses.size());
  }
  std::fprintf(stderr, "\n");
  html << "<p>median frame time " << median(ms) << " ms (mode " << o.mode << ")</p>\n";
  blvd_stats rs{};
  rs.struct_size = sizeof rs;
  check(blvd_runtime_stats(rt, &rs), rt, "stats");
  html << "<p>" << rs.loads << " cell loads, " << rs.evictions << " evictions, " << degraded
       << " frames drawn before their cell was resident (redrawn after waiting); GPU high water "
       << rs.gpu.high_water_bytes / 1048576.0 << " of " << rs.gpu.capacity_bytes / 1048576.0 << " MiB</p>\n";
  std::printf("wrote %zu frames and %s/index.html; median frame %.1f ms (mode %s); %llu cell loads, %zu frames "
              "waited for their cell; GPU %.1f of %.1f MiB\n",
              poses.size(), o.out.c_str(), median(ms), o.mode.c_str(), static_cast<unsigned long long>(rs.loads),
              degraded, rs.gpu.high_water_bytes / 1048576.0, rs.gpu.capacity_bytes / 1048576.0);
  return 0;
}

}  // namespace

void addView(CLI::App& app, Runner& runner) {
  auto o = std::make_shared<ViewOpts>();
  auto* cmd = app.add_subcommand("view", "render headless to PNG (one pose, or a drive with --path) in a render mode (--mode)");
  cmd->add_option("package", o->package, "package (.blvd)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--lat", o->lat, "eye latitude, degrees");
  cmd->add_option("--lon", o->lon, "eye longitude, degrees");
  cmd->add_option("--heading", o->heading, "view heading, degrees clockwise from north")->capture_default_str();
  cmd->add_option("--pitch", o->pitch, "view pitch, degrees (up positive)")->capture_default_str()->check(CLI::Range(-89.0, 89.0));
  cmd->add_option("--fov", o->fov, "vertical field of view, degrees")->capture_default_str()->check(CLI::Range(5.0, 150.0));
  cmd->add_option("--size", o->size, "frame size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--backend", o->backend, "auto, egl-surfaceless, egl-device or osmesa")->capture_default_str();
  cmd->add_option("--mode", o->mode, "what to draw: full, local, radius:R, single, layered or blvd (= layered)")
      ->capture_default_str();
  cmd->add_option("--path", o->path, "drive auto:N connected cells instead of one pose; -o is then a folder");
  cmd->add_option("--repeat", o->repeat, "render the pose N more times and report the median frame time")
      ->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--seed", o->seed, "seed of the auto path")->capture_default_str();
  cmd->add_option("--step", o->step, "metres between frames of a drive")->capture_default_str()->check(CLI::Range(0.5, 500.0));
  cmd->add_option("-o,--output", o->out, "PNG to write (or folder, with --path)")->required();
  cmd->add_option("--items", o->items, "one pose: also write its object ids as a PNG (RGB = block + 1, or 0x800000 | layer + 1)");
  cmd->add_option("--impostor-texture", o->impostor_texture, "how cell slots hold impostor images: rgba8 or etc2")
      ->capture_default_str()
      ->check(CLI::IsMember({"rgba8", "etc2"}));
  cmd->add_flag("--with-full", o->with_full, "a drive also writes each pose's full-model frame; index.html flips between them");
  cmd->callback([o, &runner] { runner = [o] { return run(*o); }; });
}

}  // namespace blvd::cli
