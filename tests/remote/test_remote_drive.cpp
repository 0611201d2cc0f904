// A runtime on a package served over HTTP (blvd_runtime_desc.package_path a
// URL) against the same runtime on the local file: a cold start fetches the
// table pages and the blobs the first cell reads and nothing else; a drive draws the same
// frames as the local file's, its cache never above cache_bytes after any
// frame; a drive through a misbehaving link (cut bodies, 200 for a range,
// 503 with Retry-After, a 30 s tunnel) keeps drawing while the link is down
// and ends with the same poses and frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "geo/local_frame.h"
#include "remote_drive.h"
#include "stream/city.h"

using namespace blvd_test;

namespace {

const blvd::stream::City& localCity() {
  static blvd::stream::City city;
  static const bool opened = [] {
    std::string err;
    const bool ok = city.open(BLVD_TEST_PACKAGE, err, blvd::stream::City::Tables::All,
                              blvd::stream::City::GraphTables::Paged) == blvd::core::Status::Ok;
    EXPECT_TRUE(ok) << err;
    return ok;
  }();
  (void)opened;
  return city;
}

uint64_t cellBlobBytes(uint32_t cell, std::vector<uint32_t>& blobs) {
  const blvd::stream::City& city = localCity();
  city.cellBlobs(cell, nullptr, 0, blobs);
  uint64_t n = 0;
  for (const uint32_t b : blobs) n += city.package().blobInfo(b).size;
  return n;
}

// Bytes of the blobs `cells` draw, each blob once, plus `per_blob` for each.
uint64_t uniqueBlobBytes(const std::vector<uint32_t>& cells, uint64_t per_blob = 0) {
  std::vector<uint32_t> all, blobs;
  for (const uint32_t c : cells) {
    cellBlobBytes(c, blobs);
    all.insert(all.end(), blobs.begin(), blobs.end());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  uint64_t n = 0;
  for (const uint32_t b : all) n += localCity().package().blobInfo(b).size + per_blob;
  return n;
}

// Where two frames of the same pose differ, what each runtime drew there (the
// item ids of their last frames: block + 1, impostor layers with the
// BLVD_ITEM_IMPOSTOR bit), the most frequent pairs first, and what each has
// loaded, reused and evicted: enough to tell a slot's content from a cell
// choice when a drive's frames part.
std::string whatDiffers(blvd_runtime* a, blvd_runtime* b, const std::vector<uint8_t>& fa,
                        const std::vector<uint8_t>& fb, const blvd_runtime_desc& d) {
  std::vector<uint32_t> ia(size_t(d.width) * d.height), ib(ia.size());
  if (blvd_read_items(a, ia.data(), ia.size()) != BLVD_OK || blvd_read_items(b, ib.data(), ib.size()) != BLVD_OK)
    return "items not read";
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> pairs;
  for (size_t k = 0; k < ia.size(); ++k)
    if (pixelDiffers(fa, fb, k)) ++pairs[{ia[k], ib[k]}];
  std::vector<std::pair<uint32_t, std::pair<uint32_t, uint32_t>>> top;
  for (const auto& [ids, n] : pairs) top.push_back({n, ids});
  std::sort(top.rbegin(), top.rend());
  std::ostringstream os;
  os << "items local/remote (pixels):";
  for (size_t k = 0; k < top.size() && k < 6; ++k)
    os << std::hex << " 0x" << top[k].second.first << "/0x" << top[k].second.second << std::dec << " (" << top[k].first
       << ")";
  for (blvd_runtime* rt : {a, b}) {
    const blvd_stats s = stats(rt);
    os << (rt == a ? "; local" : "; remote") << " loads " << s.loads << " evictions " << s.evictions
       << " blocks reused " << s.blocks_reused << " load errors " << s.load_errors;
  }
  return os.str();
}

// Draws each pose of `dr` in both runtimes (local first) and fails for the
// first three whose frames differ; `after` runs after each pose.
template <typename After>
void expectSameFrames(blvd_runtime* local, const blvd_runtime_desc& dl, blvd_runtime* remote,
                      const blvd_runtime_desc& du, const Drive& dr, After&& after) {
  uint32_t differing = 0;
  for (size_t i = 0; i < dr.poses.size(); ++i) {
    const std::vector<uint8_t> fl = wholeFrame(local, dr.poses[i], dl), fu = wholeFrame(remote, dr.poses[i], du);
    if (fl != fu && differing++ < 3)
      ADD_FAILURE() << "pose " << i << " (cell " << dr.poses[i].cell << "): " << differingPixels(fl, fu)
                    << " pixels differ; " << whatDiffers(local, remote, fl, fu, dl);
    after(i);
  }
}

// A runtime on `url` with a 64 MiB cache in `cache`, `route` set or not, its
// first pose drawn whole.
struct FirstFrame {
  std::string url, cache;
  blvd_runtime_desc d;
  Rt r;
  FirstFrame(std::string u, std::string c, const Drive& dr, bool route)
      : url(std::move(u)), cache(std::move(c)), d(RemoteDriveTest::urlDesc(url, cache, 64ull << 20)) {
    EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
    if (!r.rt) return;
    if (route) {
      EXPECT_EQ(blvd_set_route(r.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
    }
    wholeFrame(r.rt, dr.poses[0], d);
  }
};

}  // namespace

TEST_F(RemoteDriveTest, AColdStartFetchesOnlyWhatTheFirstCellReads) {
  const Drive dr = impostorDrive(1, 10.0);
  ASSERT_FALSE(dr.cells.empty());
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/cold";
  const blvd_runtime_desc d = urlDesc(url, cache, 64ull << 20);
  Rt r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  const uint32_t route[] = {dr.cells[0]};  // nothing predicted past it
  ASSERT_EQ(blvd_set_route(r.rt, route, 1), BLVD_OK);
  const DrivePose& p = dr.poses[dr.poses.size() / 2];  // mid-cell: the cell the runtime picks
  ASSERT_EQ(p.cell, dr.cells[0]);
  wholeFrame(r.rt, p, d);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  ASSERT_EQ(blvd_render(r.rt, &fs), BLVD_OK);
  ASSERT_EQ(fs.cell, dr.cells[0]);
  const blvd_stats s = stats(r.rt);
  std::vector<uint32_t> blobs;
  const uint64_t cell_bytes = cellBlobBytes(dr.cells[0], blobs);
  // The first 16 KiB (header, directory), TPCR and the blob index in one
  // request, the table pages the first frame read (4 KiB each, neighbours
  // together), then the cell's blobs, neighbours in one request.
  const blvd::package::PackageReader& pkg = localCity().package();
  uint64_t tables = 0;
  for (const blvd::package::SectionInfo& si : pkg.sections())
    if (si.tag != blvd::package::kSectionBlobData) tables += si.size;
  const uint64_t index = pkg.section(blvd::package::kSectionBlobIndex).size +
                         pkg.section(blvd::package::kSectionTablePages).size;
  ASSERT_GE(s.link_table_bytes, 16384 + index);
  const uint64_t pages = s.link_table_bytes - 16384 - index;
  EXPECT_GE(s.link_bytes - s.link_table_bytes, cell_bytes);
  EXPECT_LE(s.link_bytes - s.link_table_bytes, cell_bytes + (blobs.size() - 1) * 4096);  // gaps under 4 KiB
  EXPECT_LE(pages, tables / 3) << "the first frame read a third of the tables";
  EXPECT_LE(s.link_requests, 2 + blobs.size() + pages / 4096);
  EXPECT_EQ(s.cache_misses, 0u);  // every blob was fetched before its decode, and served by the cache
  EXPECT_EQ(s.loads, 1u);
  EXPECT_GE(s.cache_hits, blobs.size());
  std::printf("cold start: %llu requests, %llu bytes (table pages %llu of %llu, cell %u's %zu blobs %llu)\n",
              (unsigned long long)s.link_requests, (unsigned long long)s.link_bytes, (unsigned long long)pages,
              (unsigned long long)tables, dr.cells[0], blobs.size(), (unsigned long long)cell_bytes);
}

// Online, once the link has nothing else to do, the tables the first frames
// did not read arrive too: the mirror then holds every table, each section
// whole under its CRC, for a drive on without the link.
TEST_F(RemoteDriveTest, OnlineTheRestOfTheTablesArriveOnceTheLinkIsIdle) {
  const Drive dr = impostorDrive(1, 10.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/fill";
  const blvd_runtime_desc d = urlDesc(url, cache, 64ull << 20);
  Rt r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_route(r.rt, dr.cells.data(), 1), BLVD_OK);
  wholeFrame(r.rt, dr.poses[0], d);
  const uint64_t first = stats(r.rt).link_table_bytes;
  uint64_t tables = 0;
  for (const blvd::package::SectionInfo& si : localCity().package().sections())
    if (si.tag != blvd::package::kSectionBlobData) tables += si.size;
  ASSERT_LT(first, tables);
  // Every table section of the mirror whole under its CRC (the first 16 KiB
  // came with the header: less than the tables' bytes cross the link).
  auto complete = [&] {
    blvd::package::PackageReader mirror;
    std::string err;
    if (blvd::package::PackageReader::open(cache + "/tables.blvd", mirror, err) != blvd::core::Status::Ok) return false;
    for (const blvd::package::SectionInfo& si : mirror.sections()) {
      blvd::package::Span s;
      if (si.tag != blvd::package::kSectionBlobData && mirror.checkedSection(si.tag, s, err) != blvd::core::Status::Ok)
        return false;
    }
    return true;
  };
  ASSERT_FALSE(complete());
  for (int i = 0; i < 600 && !complete(); ++i) {
    render(r.rt, dr.poses[0]);
    ::usleep(50000);
  }
  EXPECT_TRUE(complete());
  EXPECT_LE(stats(r.rt).link_table_bytes, tables + 16384);  // each page once
}

TEST_F(RemoteDriveTest, ADriveDrawsWhatTheLocalFileDrawsInACacheThatNeverGrowsPastItsBytes) {
  const Drive dr = impostorDrive(24, 12.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/small";
  // The least the runtime takes, the tables and the package's largest blob,
  // and a little: less than the route's blobs, so blobs are evicted.
  uint64_t tables = 0, largest = 0;
  const blvd::package::PackageReader& pkg = localCity().package();
  for (const blvd::package::SectionInfo& si : pkg.sections())
    if (si.tag != blvd::package::kSectionBlobData) tables += si.size;
  for (uint32_t b = 0; b < pkg.blobCount(); ++b) largest = std::max(largest, pkg.blobInfo(b).size);
  const uint64_t route = uniqueBlobBytes(dr.cells);
  const uint64_t cache_bytes = tables + largest + 16384;
  ASSERT_LT(cache_bytes, tables + route);
  const blvd_runtime_desc dl = localDesc(), du = urlDesc(url, cache, cache_bytes);
  Rt local, remote;
  ASSERT_EQ(blvd_runtime_create(&dl, &local.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&du, &remote.rt), BLVD_OK) << blvd_last_error(nullptr);
  for (blvd_runtime* rt : {local.rt, remote.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  expectSameFrames(local.rt, dl, remote.rt, du, dr, [&](size_t i) {
    EXPECT_LE(stats(remote.rt).cache_bytes, cache_bytes) << "pose " << i;
    EXPECT_LE(diskBytes(cache), cache_bytes + 4096) << "pose " << i;  // the mirror's last block
  });
  const blvd_stats s = stats(remote.rt);
  EXPECT_EQ(s.load_errors, 0u);
  EXPECT_GT(s.cache_hits, 0u);
  // More blob bytes than every blob of the route once: blobs were evicted and fetched again.
  EXPECT_GT(s.cache_evictions, 0u);
  const uint64_t once = uniqueBlobBytes(dr.cells);
  EXPECT_GT(s.link_bytes - s.link_table_bytes, once);
}

// ETC2 slot atlases (decision 0039) over the link, where the plan sizes the
// atlas and the staging from the header's maxima on the 32-texel grid: the
// frames are those of the local file's ETC2 slots.
TEST_F(RemoteDriveTest, Etc2SlotsOverTheLinkDrawWhatLocalEtc2SlotsDraw) {
  const Drive dr = impostorDrive(8, 12.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/etc2";
  blvd_runtime_desc dl = localDesc(), du = urlDesc(url, cache, 64ull << 20);
  dl.impostor_texture = du.impostor_texture = BLVD_TEXTURE_ETC2;
  Rt local, remote;
  ASSERT_EQ(blvd_runtime_create(&dl, &local.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&du, &remote.rt), BLVD_OK) << blvd_last_error(nullptr);
  for (blvd_runtime* rt : {local.rt, remote.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  expectSameFrames(local.rt, dl, remote.rt, du, dr, [](size_t) {});
  EXPECT_EQ(stats(remote.rt).load_errors, 0u);
}

TEST_F(RemoteDriveTest, ADriveThroughABadLinkKeepsDrawingAndEndsWithTheSamePosesAndFrames) {
  const Drive dr = impostorDrive(10, 15.0);
  const std::string url = faults_->url("/drive/monaco.blvd"), cache = work_ + "/faults";
  const blvd_runtime_desc dl = localDesc(), du = urlDesc(url, cache, 64ull << 20);
  Rt local, remote;
  ASSERT_EQ(blvd_runtime_create(&dl, &local.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&du, &remote.rt), BLVD_OK) << blvd_last_error(nullptr);
  // The same fixes into a tracker over each: the tables came through the faults.
  blvd_tracker_desc tl{}, tu{};
  tl.struct_size = tu.struct_size = sizeof tl;
  tl.package_path = BLVD_TEST_PACKAGE;
  tu.package_path = url.c_str();
  tu.cache_path = cache.c_str();
  tu.cache_bytes = 64ull << 20;
  blvd_tracker *trl = nullptr, *tru = nullptr;
  ASSERT_EQ(blvd_tracker_create(&tl, &trl), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_tracker_create(&tu, &tru), BLVD_OK) << blvd_last_error(nullptr);
  blvd_runtime_info info{};
  info.struct_size = sizeof info;
  ASSERT_EQ(blvd_runtime_get_info(local.rt, &info), BLVD_OK);
  const blvd::geo::LocalFrame origin(info.origin_lat, info.origin_lon);

  // The route's first two cells only, until the tunnel: then the whole route, whose cells the link
  // prefetch must fetch inside the tunnel.
  const size_t tunnel_at = 1;
  for (blvd_runtime* rt : {local.rt, remote.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), 2), BLVD_OK);
  uint32_t differing = 0, frames_in_tunnel = 0;
  for (size_t i = 0; i < dr.poses.size(); ++i) {
    const DrivePose& p = dr.poses[i];
    if (i == tunnel_at) {  // 30 s without an answer, drawing all along, the cell not yet there
      for (blvd_runtime* rt : {local.rt, remote.rt})
        ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
      const uint64_t requests_before = stats(remote.rt).link_requests;
      std::ofstream(work_ + "/www/.down") << "tunnel";
      const auto t0 = std::chrono::steady_clock::now();
      blvd_frame_stats fs{};
      fs.struct_size = sizeof fs;
      while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30)) {
        // Held up in the tunnel at this pose (a pose that jumped about would
        // give the cell choice another history than the local drive's).
        ASSERT_EQ(blvd_set_pose_local(remote.rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
        ASSERT_EQ(blvd_render(remote.rt, &fs), BLVD_OK) << blvd_last_error(remote.rt);
        ++frames_in_tunnel;
      }
      std::filesystem::remove(work_ + "/www/.down");
      EXPECT_GT(stats(remote.rt).link_requests, requests_before) << "nothing asked of the link in the tunnel";
    }
    const std::vector<uint8_t> fl = wholeFrame(local.rt, p, dl), fu = wholeFrame(remote.rt, p, du);
    if (fl != fu && differing++ < 3)
      ADD_FAILURE() << "pose " << i << " (cell " << p.cell << "): " << differingPixels(fl, fu) << " pixels differ; "
                    << whatDiffers(local.rt, remote.rt, fl, fu, dl);
    blvd_gnss_fix fix{};
    fix.struct_size = sizeof fix;
    fix.t = double(i);
    double h = 0;
    origin.reverse({p.x, p.y, 0}, fix.lat, fix.lon, h);
    fix.speed_mps = 12.f, fix.track_deg = float(p.heading_deg), fix.hdop = 1.f, fix.h_acc_m = 3.f;
    fix.mode = BLVD_GNSS_MODE_3D;
    fix.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK |
                BLVD_GNSS_HAS_HDOP | BLVD_GNSS_HAS_HACC;
    ASSERT_EQ(blvd_tracker_feed_gnss(trl, &fix), BLVD_OK);
    ASSERT_EQ(blvd_tracker_feed_gnss(tru, &fix), BLVD_OK);
    blvd_pose a{}, b{};
    a.struct_size = b.struct_size = sizeof a;
    ASSERT_EQ(blvd_tracker_get_pose(trl, fix.t, &a), BLVD_OK);
    ASSERT_EQ(blvd_tracker_get_pose(tru, fix.t, &b), BLVD_OK);
    EXPECT_EQ(a.cell, b.cell) << "fix " << i;
    EXPECT_EQ(a.x, b.x) << "fix " << i;
    EXPECT_EQ(a.y, b.y) << "fix " << i;
  }
  blvd_tracker_destroy(trl);
  blvd_tracker_destroy(tru);
  const blvd_stats s = stats(remote.rt);
  EXPECT_GE(frames_in_tunnel, 10u) << "frames waited for the link";
  EXPECT_EQ(s.load_errors, 0u);
  EXPECT_GT(s.link_requests, 13u);  // every fault of the 13-request cycle came round
  std::printf("bad link: %u frames drawn in the 30 s tunnel, %llu link waits, %llu requests\n", frames_in_tunnel,
              (unsigned long long)s.link_waits, (unsigned long long)s.link_requests);
}

TEST_F(RemoteDriveTest, TheLinkPrefetchesTheRouteAheadBeyondTheCellSlots) {
  const Drive dr = impostorDrive(40, 15.0);
  FirstFrame f(nginx_->url("/monaco.blvd"), work_ + "/ahead", dr, true);
  ASSERT_TRUE(f.r.rt);
  Rt& r = f.r;
  const blvd_runtime_desc& d = f.d;
  blvd_stats s = stats(r.rt);
  EXPECT_GE(s.prefetch_horizon_m, 400.0);  // no speed from host-set poses: the least horizon
  // The slots hold 4 cells; the prefetch fills the disk cache along the route up to its horizon.
  for (int k = 0; k < 500 && s.cached_ahead_m < 400.0; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    wholeFrame(r.rt, dr.poses[0], d);
    s = stats(r.rt);
  }
  EXPECT_GE(s.cached_ahead_m, 400.0);
  // Metered: no prefetch; the drive goes on, the current and next cells fetched as it needs them.
  ASSERT_EQ(blvd_set_link_mode(r.rt, BLVD_LINK_METERED), BLVD_OK);
  const uint64_t requests = stats(r.rt).link_requests;
  for (size_t i = 0; i < dr.poses.size(); i += 4) wholeFrame(r.rt, dr.poses[i], d);
  s = stats(r.rt);
  std::printf("prefetch: %.0f m cached ahead, horizon %.0f m; metered drive: %llu more requests\n", s.cached_ahead_m,
              s.prefetch_horizon_m, (unsigned long long)(s.link_requests - requests));
  EXPECT_EQ(s.load_errors, 0u);
}

// Metered from the start: the current cell and the next on the route, however
// long the link stays idle (online, the prefetch fetches 400 m ahead here).
TEST_F(RemoteDriveTest, MeteredFetchesTheCurrentAndTheNextCellOnly) {
  const Drive dr = impostorDrive(40, 15.0);
  const std::string url = nginx_->url("/monaco.blvd"), cache = work_ + "/metered";
  blvd_runtime_desc d = urlDesc(url, cache, 64ull << 20);
  d.link_mode = BLVD_LINK_METERED;
  Rt r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_route(r.rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  ASSERT_EQ(dr.poses[0].cell, dr.cells[0]);
  wholeFrame(r.rt, dr.poses[0], d);
  for (int k = 0; k < 100; ++k) {
    render(r.rt, dr.poses[0]);
    ::usleep(20000);
  }
  const blvd_stats s = stats(r.rt);
  const std::vector<uint32_t> two(dr.cells.begin(), dr.cells.begin() + 2);
  double two_m = 0;
  for (const uint32_t c : two) two_m += localCity().streets().halfedge(c).length;
  const uint64_t allowed = uniqueBlobBytes(two, 4096);  // and a gap each
  EXPECT_GT(s.link_bytes - s.link_table_bytes, 0u);
  EXPECT_LE(s.link_bytes - s.link_table_bytes, allowed);
  EXPECT_LE(s.cached_ahead_m, two_m + 1.0);
  EXPECT_EQ(s.load_errors, 0u);
}

TEST_F(RemoteDriveTest, WithoutARouteThePrefetchFetchesEveryWayAheadPastTheSlots) {
  const Drive dr = impostorDrive(40, 15.0);
  FirstFrame f(nginx_->url("/monaco.blvd"), work_ + "/straight", dr, false);
  ASSERT_TRUE(f.r.rt);
  Rt& r = f.r;
  const blvd_runtime_desc& d = f.d;
  blvd_stats s = stats(r.rt);
  // Until the link goes quiet: every way within the horizon fetched.
  for (uint64_t last = ~0ull; s.link_requests != last;) {
    last = s.link_requests;
    for (int k = 0; k < 50; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      wholeFrame(r.rt, dr.poses[0], d);
    }
    s = stats(r.rt);
  }
  std::printf("no route: %.0f m straight on cached, horizon %.0f m, %llu requests, %.2f MB cached\n", s.cached_ahead_m,
              s.prefetch_horizon_m, (unsigned long long)s.link_requests, double(s.cache_bytes) / 1e6);
  // The slots hold 4 cells; the ways within 400 m are many more.
  std::vector<uint32_t> blobs;
  uint64_t four_cells = 0;
  for (uint32_t k = 0; k < 4; ++k) four_cells += cellBlobBytes(dr.cells[k], blobs);
  EXPECT_GT(s.cache_bytes, 767568 + 2 * four_cells);
  EXPECT_EQ(s.load_errors, 0u);
}
