#include "bake/dem.h"

#include <zip.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>

#include "core/status.h"

namespace blvd::bake {

namespace {

constexpr int16_t kVoid = -32768;

[[noreturn]] void fail(core::Status st, const std::string& what) { throw core::Error(st, what); }

std::string baseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool endsWith(const std::string& s, const char* suffix) {
  const size_t n = std::char_traits<char>::length(suffix);
  if (s.size() < n) return false;
  for (size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - n + i])) != suffix[i]) return false;
  return true;
}

std::vector<uint8_t> readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(core::Status::Io, path + ": cannot open the DEM file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) fail(core::Status::Io, path + ": cannot read the DEM file");
  return bytes;
}

// The one .hgt entry of a zip held in `bytes`, its name in `entry`.
std::vector<uint8_t> unzipHgt(const std::vector<uint8_t>& bytes, const std::string& path, std::string& entry) {
  zip_error_t ze;
  zip_error_init(&ze);
  zip_source_t* src = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &ze);
  zip_t* z = src ? zip_open_from_source(src, ZIP_RDONLY, &ze) : nullptr;
  if (!z) {
    const std::string why = zip_error_strerror(&ze);
    if (src) zip_source_free(src);
    zip_error_fini(&ze);
    fail(core::Status::Corrupt, path + ": not a zip archive libzip can read: " + why);
  }
  zip_error_fini(&ze);
  std::unique_ptr<zip_t, void (*)(zip_t*)> own(z, [](zip_t* a) { zip_discard(a); });
  const zip_int64_t count = zip_get_num_entries(z, 0);
  zip_int64_t found = -1;
  for (zip_int64_t i = 0; i < count; ++i) {
    const char* name = zip_get_name(z, zip_uint64_t(i), 0);
    if (!name || !endsWith(name, ".hgt")) continue;
    if (found >= 0) fail(core::Status::Corrupt, path + ": more than one .hgt in the zip (" + entry + ", " + name + ")");
    found = i;
    entry = name;
  }
  if (found < 0) fail(core::Status::Corrupt, path + ": no .hgt file in the zip");
  zip_stat_t st;
  if (zip_stat_index(z, zip_uint64_t(found), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE))
    fail(core::Status::Corrupt, path + ": " + entry + ": no size in the zip: " + zip_strerror(z));
  if (st.size != 2ull * 1201 * 1201 && st.size != 2ull * 3601 * 3601)
    fail(core::Status::Corrupt, path + ": " + entry + ": " + std::to_string(st.size) +
                                    " bytes is not an SRTM tile (1201 x 1201 or 3601 x 3601 samples of 2 bytes)");
  std::vector<uint8_t> out(static_cast<size_t>(st.size));
  zip_file_t* f = zip_fopen_index(z, zip_uint64_t(found), 0);
  if (!f) fail(core::Status::Corrupt, path + ": " + entry + ": " + zip_strerror(z));
  const zip_int64_t got = zip_fread(f, out.data(), out.size());
  const std::string why = got < 0 ? zip_file_strerror(f) : "";
  zip_fclose(f);
  if (got != zip_int64_t(out.size()))
    fail(core::Status::Corrupt, path + ": " + entry + ": read " + std::to_string(got) + " of " +
                                    std::to_string(out.size()) + " bytes" + (why.empty() ? "" : ": " + why));
  return out;
}

// For one grid direction (dr, dc), adds to each void's sums the nearest valid
// sample from it along that direction, weighted by 1 / distance. One sweep
// that meets (r + dr, c + dc) before (r, c) carries the nearest along:
// O(n²) per direction, however large the voids.
void addDirection(const std::vector<float>& h, const std::vector<bool>& is_void, int n, int dr, int dc,
                  std::vector<float>& sum, std::vector<float>& weight) {
  std::vector<float> near_value(h.size());
  std::vector<int> near_steps(h.size(), 0);  // 0: none in that direction
  const double unit = std::sqrt(double(dr * dr + dc * dc));
  for (int k = 0; k < n; ++k) {
    const int r = dr > 0 ? n - 1 - k : k;
    for (int m = 0; m < n; ++m) {
      const int c = dc > 0 ? n - 1 - m : m;
      const int rr = r + dr, cc = c + dc;
      const size_t i = size_t(r) * size_t(n) + size_t(c);
      if (rr < 0 || cc < 0 || rr >= n || cc >= n) continue;
      const size_t j = size_t(rr) * size_t(n) + size_t(cc);
      if (!is_void[j]) {
        near_value[i] = h[j];
        near_steps[i] = 1;
      } else if (near_steps[j] > 0) {
        near_value[i] = near_value[j];
        near_steps[i] = near_steps[j] + 1;
      }
      if (is_void[i] && near_steps[i] > 0) {
        const double w = 1.0 / (near_steps[i] * unit);
        sum[i] += float(near_value[i] * w);
        weight[i] += float(w);
      }
    }
  }
}

}  // namespace

std::string srtmTileName(int lat0, int lon0) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%c%02d%c%03d", lat0 < 0 ? 'S' : 'N', std::abs(lat0), lon0 < 0 ? 'W' : 'E',
                std::abs(lon0));
  return buf;
}

bool parseSrtmName(const std::string& path, int& lat0, int& lon0) {
  const std::string name = baseName(path);
  if (name.size() < 7) return false;
  const char ns = char(std::toupper(static_cast<unsigned char>(name[0])));
  const char ew = char(std::toupper(static_cast<unsigned char>(name[3])));
  auto digits = [&](size_t at, size_t n) {
    int v = 0;
    for (size_t i = at; i < at + n; ++i) {
      if (!std::isdigit(static_cast<unsigned char>(name[i]))) return -1;
      v = v * 10 + (name[i] - '0');
    }
    return v;
  };
  const int lat = digits(1, 2), lon = digits(4, 3);
  if ((ns != 'N' && ns != 'S') || (ew != 'E' && ew != 'W') || lat < 0 || lon < 0) return false;
  if (name.size() > 7 && name[7] != '.') return false;
  lat0 = ns == 'S' ? -lat : lat;
  lon0 = ew == 'W' ? -lon : lon;
  return lat0 >= -90 && lat0 < 90 && lon0 >= -180 && lon0 < 180;
}

uint32_t fillVoids(std::vector<float>& h, int n, float void_value, const std::string& source) {
  std::vector<bool> is_void(h.size());
  uint32_t voids = 0;
  for (size_t i = 0; i < h.size(); ++i) voids += (is_void[i] = h[i] == void_value);
  if (voids == 0) return 0;
  if (voids == h.size()) fail(core::Status::Corrupt, source + ": every sample is a void");
  static constexpr int kDirs[8][2] = {{-1, 0}, {-1, 1}, {0, 1}, {1, 1}, {1, 0}, {1, -1}, {0, -1}, {-1, -1}};
  std::vector<float> sum(h.size(), 0.f), weight(h.size(), 0.f);
  for (const auto& d : kDirs) addDirection(h, is_void, n, d[0], d[1], sum, weight);
  double mean = 0;  // for a void that sees no valid sample in any direction
  for (size_t i = 0; i < h.size(); ++i)
    if (!is_void[i]) mean += h[i];
  mean /= double(h.size() - voids);
  for (size_t i = 0; i < h.size(); ++i)
    if (is_void[i]) h[i] = weight[i] > 0 ? sum[i] / weight[i] : float(mean);
  return voids;
}

DemTile parseHgt(const std::vector<uint8_t>& bytes, int lat0, int lon0, const std::string& source) {
  int n = 0;
  if (bytes.size() == 2ull * 1201 * 1201) n = 1201;
  if (bytes.size() == 2ull * 3601 * 3601) n = 3601;
  if (n == 0)
    fail(core::Status::Corrupt, source + ": " + std::to_string(bytes.size()) +
                                    " bytes is not an SRTM tile (1201 x 1201 or 3601 x 3601 samples of 2 bytes)");
  DemTile t;
  t.lat0 = lat0;
  t.lon0 = lon0;
  t.n = n;
  t.source = source;
  t.h.resize(size_t(n) * size_t(n));
  for (size_t i = 0; i < t.h.size(); ++i)  // big-endian int16 metres
    t.h[i] = float(int16_t(uint16_t(bytes[2 * i]) << 8 | bytes[2 * i + 1]));
  t.voids = fillVoids(t.h, n, float(kVoid), source);
  return t;
}

DemTile parseDemFile(const std::vector<uint8_t>& bytes, const std::string& path) {
  std::string named = path;
  std::vector<uint8_t> unzipped;
  if (endsWith(path, ".zip")) {
    std::string entry;
    unzipped = unzipHgt(bytes, path, entry);
    int lat0, lon0;
    if (parseSrtmName(entry, lat0, lon0)) named = entry;  // the entry's name has the corner; else the zip's
  }
  int lat0, lon0;
  if (!parseSrtmName(named, lat0, lon0))
    fail(core::Status::InvalidArg, path + ": the name does not say which tile it is (SRTM names a tile by its "
                                          "south-west corner, as in N43E007.hgt)");
  return parseHgt(endsWith(path, ".zip") ? unzipped : bytes, lat0, lon0, path);
}

void Dem::addFile(const std::string& path) { addTile(parseDemFile(readFile(path), path)); }

void Dem::addTile(DemTile tile) {
  if (const DemTile* t = tileAt(tile.lat0, tile.lon0))
    fail(core::Status::InvalidArg, tile.source + ": tile " + srtmTileName(tile.lat0, tile.lon0) +
                                       " is already given by " + t->source);
  tiles_.push_back(std::move(tile));
}

const DemTile* Dem::tileAt(int lat0, int lon0) const {
  for (const DemTile& t : tiles_)
    if (t.lat0 == lat0 && t.lon0 == lon0) return &t;
  return nullptr;
}

double Dem::height(double lat, double lon) const {
  const DemTile* t = tileAt(int(std::floor(lat)), int(std::floor(lon)));
  if (!t) return std::numeric_limits<double>::quiet_NaN();
  const double y = (double(t->lat0) + 1.0 - lat) * (t->n - 1);  // rows from the north edge
  const double x = (lon - double(t->lon0)) * (t->n - 1);
  const int r = std::min(int(y), t->n - 2), c = std::min(int(x), t->n - 2);
  const double fy = y - r, fx = x - c;
  const double top = t->sample(r, c) * (1 - fx) + t->sample(r, c + 1) * fx;
  const double bottom = t->sample(r + 1, c) * (1 - fx) + t->sample(r + 1, c + 1) * fx;
  return top * (1 - fy) + bottom * fy;
}

void Dem::requireCovers(double lat_min, double lon_min, double lat_max, double lon_max) const {
  std::string missing;
  for (int la = int(std::floor(lat_min)); la <= int(std::floor(lat_max)); ++la)
    for (int lo = int(std::floor(lon_min)); lo <= int(std::floor(lon_max)); ++lo)
      if (!tileAt(la, lo)) missing += (missing.empty() ? "" : ", ") + srtmTileName(la, lo);
  if (missing.empty()) return;
  char box[96];
  std::snprintf(box, sizeof box, "%.4f..%.4f, %.4f..%.4f", lat_min, lat_max, lon_min, lon_max);
  fail(core::Status::InvalidArg, std::string("the DEM does not cover the city (latitude, longitude ") + box +
                                     "): no tile " + missing + " (SRTM tiles are named by their south-west corner)");
}

}  // namespace blvd::bake
