// Dem (bake/dem.h): SRTM tiles read as .hgt and as .zip, named by their
// corner; voids filled from their neighbours; bilinear heights exact on a
// plane; a DEM that does not cover a box names the missing tiles; bad files
// named. And the real tile over Monaco: its voids, the sea, Monaco-Ville.
#include <gtest/gtest.h>
#include <zip.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake/dem.h"
#include "core/status.h"

namespace {

using blvd::bake::Dem;
using blvd::bake::DemTile;

// An SRTM3 tile whose samples are `f(lat, lon)` (metres), big-endian int16.
template <class F>
std::vector<uint8_t> hgtOf(int lat0, int lon0, F f) {
  const int n = 1201;
  std::vector<uint8_t> bytes(size_t(n) * n * 2);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double lat = lat0 + 1.0 - double(r) / (n - 1), lon = lon0 + double(c) / (n - 1);
      const auto v = uint16_t(int16_t(f(lat, lon, r, c)));
      const size_t i = (size_t(r) * n + c) * 2;
      bytes[i] = uint8_t(v >> 8);
      bytes[i + 1] = uint8_t(v & 0xff);
    }
  return bytes;
}

std::string writeFile(const std::string& name, const std::vector<uint8_t>& bytes) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  return path;
}

// A zip holding `entry` with `bytes` (deflated), written with libzip.
std::string writeZip(const std::string& name, const std::string& entry, const std::vector<uint8_t>& bytes) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::filesystem::remove(path);
  int err = 0;
  zip_t* z = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
  EXPECT_NE(z, nullptr);
  zip_source_t* s = zip_source_buffer(z, bytes.data(), bytes.size(), 0);
  EXPECT_GE(zip_file_add(z, entry.c_str(), s, ZIP_FL_OVERWRITE), 0);
  EXPECT_EQ(zip_close(z), 0);
  return path;
}

std::string thrown(const std::function<void()>& f) {
  try {
    f();
  } catch (const blvd::core::Error& e) {
    return e.what();
  }
  return "";
}

TEST(Dem, TileNamesAreTheirSouthWestCorner) {
  int lat, lon;
  ASSERT_TRUE(blvd::bake::parseSrtmName("/data/N43E007.hgt", lat, lon));
  EXPECT_EQ(lat, 43);
  EXPECT_EQ(lon, 7);
  ASSERT_TRUE(blvd::bake::parseSrtmName("s12w077.hgt.zip", lat, lon));
  EXPECT_EQ(lat, -12);
  EXPECT_EQ(lon, -77);
  EXPECT_FALSE(blvd::bake::parseSrtmName("monaco.hgt", lat, lon));
  EXPECT_FALSE(blvd::bake::parseSrtmName("N4XE007.hgt", lat, lon));
  EXPECT_FALSE(blvd::bake::parseSrtmName("N43E0071.hgt", lat, lon));
  EXPECT_EQ(blvd::bake::srtmTileName(-12, -77), "S12W077");
  EXPECT_EQ(blvd::bake::srtmTileName(43, 7), "N43E007");
}

// A plane in degrees: bilinear interpolation reproduces it between samples
// (up to the int16 rounding of the samples themselves).
TEST(Dem, HeightsAreBilinearAndTheZipReadsAsTheHgt) {
  auto plane = [](double lat, double lon, int, int) { return std::lround(100.0 + 900.0 * (lat - 43) - 400.0 * (lon - 7)); };
  const std::vector<uint8_t> bytes = hgtOf(43, 7, plane);
  Dem hgt, zipped;
  hgt.addFile(writeFile("N43E007.hgt", bytes));
  zipped.addFile(writeZip("blvd_test_dem.zip", "N43E007.hgt", bytes));  // the corner from the entry's name
  ASSERT_EQ(hgt.tiles().size(), 1u);
  EXPECT_EQ(hgt.tiles()[0].n, 1201);
  EXPECT_EQ(hgt.tiles()[0].voids, 0u);
  for (double lat = 43.0; lat <= 44.0; lat += 0.0937)
    for (double lon = 7.0; lon < 8.0; lon += 0.0711) {
      const double want = 100.0 + 900.0 * (lat - 43) - 400.0 * (lon - 7);
      EXPECT_NEAR(hgt.height(lat, lon), want, 0.5) << lat << " " << lon;
      EXPECT_EQ(zipped.height(lat, lon), hgt.height(lat, lon));
    }
  EXPECT_TRUE(std::isnan(hgt.height(42.5, 7.5)));
  EXPECT_TRUE(std::isnan(hgt.height(43.5, 8.5)));
}

// Voids on a plane (a 20 x 30 hole and single samples) take the weighted mean
// of the nearest valid sample in the eight directions: on a plane, within
// the plane's change across the hole.
TEST(Dem, VoidsAreFilledFromTheirNeighbours) {
  auto holed = [](double lat, double lon, int r, int c) -> long {
    if ((r >= 500 && r < 520 && c >= 300 && c < 330) || (r == 7 && c == 9) || (r == 0 && c == 0)) return -32768;
    return std::lround(50.0 + 200.0 * (lat - 43) + 100.0 * (lon - 7));
  };
  const DemTile t = blvd::bake::parseHgt(hgtOf(43, 7, holed), 43, 7, "holed.hgt");
  EXPECT_EQ(t.voids, 20u * 30u + 2u);
  auto plane = [&](int r, int c) { return 50.0 + 200.0 * (1.0 - r / 1200.0) + 100.0 * (c / 1200.0); };
  for (int r = 500; r < 520; ++r)
    for (int c = 300; c < 330; ++c) EXPECT_NEAR(t.sample(r, c), plane(r, c), 2.5) << r << " " << c;
  EXPECT_NEAR(t.sample(7, 9), plane(7, 9), 1.0);
  EXPECT_NEAR(t.sample(0, 0), plane(0, 0), 1.0);  // a corner: three directions only
  // A tile of voids only cannot be filled.
  auto none = [](double, double, int, int) { return -32768L; };
  EXPECT_NE(thrown([&] { blvd::bake::parseHgt(hgtOf(43, 7, none), 43, 7, "void.hgt"); }).find("void.hgt: every sample is a void"),
            std::string::npos);
}

TEST(Dem, ADemThatDoesNotCoverTheCityNamesTheMissingTiles) {
  Dem dem;
  dem.addTile(blvd::bake::parseHgt(hgtOf(43, 7, [](double, double, int, int) { return 10L; }), 43, 7, "a.hgt"));
  EXPECT_NO_THROW(dem.requireCovers(43.70, 7.40, 43.76, 7.49));
  const std::string why = thrown([&] { dem.requireCovers(43.70, 7.90, 44.10, 8.10); });
  EXPECT_NE(why.find("the DEM does not cover the city"), std::string::npos) << why;
  EXPECT_NE(why.find("no tile N43E008, N44E007, N44E008"), std::string::npos) << why;
  // The same tile twice is a mistake, named.
  EXPECT_NE(thrown([&] { dem.addTile(blvd::bake::parseHgt(hgtOf(43, 7, [](double, double, int, int) { return 1L; }), 43, 7, "b.hgt")); })
                .find("b.hgt: tile N43E007 is already given by a.hgt"),
            std::string::npos);
}

TEST(Dem, BadFilesAreNamed) {
  Dem dem;
  const std::string small = writeFile("N43E007.hgt", std::vector<uint8_t>(1000, 0));
  EXPECT_NE(thrown([&] { dem.addFile(small); }).find(small + ": 1000 bytes is not an SRTM tile"), std::string::npos);
  const std::string nameless = writeFile("monaco.hgt", std::vector<uint8_t>(2 * 1201 * 1201, 0));
  EXPECT_NE(thrown([&] { dem.addFile(nameless); }).find("the name does not say which tile it is"), std::string::npos);
  const std::string not_zip = writeFile("N43E007.hgt.zip", std::vector<uint8_t>(64, 'x'));
  EXPECT_NE(thrown([&] { dem.addFile(not_zip); }).find("not a zip archive"), std::string::npos);
  const std::string no_hgt = writeZip("N43E007.zip", "readme.txt", std::vector<uint8_t>(10, 'a'));
  EXPECT_NE(thrown([&] { dem.addFile(no_hgt); }).find("no .hgt file in the zip"), std::string::npos);
  EXPECT_NE(thrown([&] { dem.addFile("/nonexistent/N43E007.hgt"); }).find("cannot open"), std::string::npos);
  EXPECT_TRUE(dem.empty());
}

// The committed SRTM3 tile (data/dem, LICENSE.md there): 1,595 voids, the sea
// at 0 m off the harbour, the top of Monaco-Ville's rock at about 66 m (the
// spot check in ../shared/data/SOURCES.md), and the slope behind Monte Carlo
// climbing well above the harbour.
TEST(Dem, TheMonacoTile) {
  Dem dem;
  dem.addFile(std::string(BLVD_DATA_DIR) + "/dem/N43E007.hgt.zip");
  ASSERT_EQ(dem.tiles().size(), 1u);
  EXPECT_EQ(dem.tiles()[0].voids, 1595u);
  EXPECT_NEAR(dem.height(43.7200, 7.4400), 0.0, 1.0);  // the sea south-east of Port Hercule
  EXPECT_NEAR(dem.height(43.7310, 7.4230), 66.0, 8.0);  // the top of the rock of Monaco-Ville (65 m here)
  EXPECT_GT(dem.height(43.7470, 7.4300), 80.0);  // above Monte Carlo, towards the Moyenne Corniche
  EXPECT_NO_THROW(dem.requireCovers(43.72, 7.40, 43.76, 7.44));
  std::printf("Monaco: sea %.1f m, Monaco-Ville %.1f m, above Monte Carlo %.1f m\n", dem.height(43.7200, 7.4400),
              dem.height(43.7310, 7.4230), dem.height(43.7470, 7.4300));
}

}  // namespace
