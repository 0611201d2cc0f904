// Dem: ground heights from SRTM tiles, for the bake's terrain.
//
// An SRTM `.hgt` tile covers 1° × 1° from its south-west corner, named by it
// (N43E007.hgt: latitude 43..44 N, longitude 7..8 E). It holds n × n
// big-endian int16 metres, rows from north to south, columns from west to
// east; n is 1201 (SRTM3, 3 arc-seconds) or 3601 (SRTM1, 1 arc-second), and
// the edge rows and columns repeat the neighbouring tiles'. -32768 marks a
// void. A tile is read from the `.hgt` file or from a `.zip` that holds one
// (as USGS and most mirrors ship them).
//
// Voids are filled when a tile is read, from the tile's own valid samples:
// each void takes the inverse-distance-weighted mean of the nearest valid
// sample in each of the eight grid directions (as GDAL's FillNodata searches
// outwards from a void, without its smoothing passes). Filled samples never
// feed other voids, so the result does not depend on the order of the scan.
//
// Heights between samples are bilinear. Errors (an unreadable file, a size
// that is no SRTM tile, a name without a corner, a tile of voids only, a
// city the tiles do not cover) throw core::Error naming the file or the
// missing tiles.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace blvd::bake {

struct DemTile {
  int lat0 = 0, lon0 = 0;  // south-west corner, degrees
  int n = 0;               // samples per row and per column
  std::vector<float> h;    // n × n metres, row 0 the northern edge
  uint32_t voids = 0;      // samples that were voids, now filled
  std::string source;      // the file it came from
  float sample(int row, int col) const { return h[size_t(row) * size_t(n) + size_t(col)]; }
};

// "N43E007" for the tile whose south-west corner is 43 N, 7 E.
std::string srtmTileName(int lat0, int lon0);
// The corner from a file name such as "N43E007.hgt", "n43e007.hgt.zip" or
// "/path/S12W077.hgt"; false when the name carries none.
bool parseSrtmName(const std::string& path, int& lat0, int& lon0);

// Reads a tile from `bytes` (the .hgt's contents), named `source` in errors;
// fills its voids. Throws core::Error (Corrupt) for a size that is no SRTM
// tile or a tile without a valid sample.
DemTile parseHgt(const std::vector<uint8_t>& bytes, int lat0, int lon0, const std::string& source);
// Fills the voids (value `void_value`) of an n × n grid as above; returns how
// many there were. Throws core::Error when every sample is a void.
uint32_t fillVoids(std::vector<float>& h, int n, float void_value, const std::string& source);

// A tile from a file's bytes: a .hgt, or (the path ends in .zip) a zip with
// one .hgt inside; its corner from the entry's or the path's name. What
// Dem::addFile reads, and the DEM fuzz target's entry point.
DemTile parseDemFile(const std::vector<uint8_t>& bytes, const std::string& path);

class Dem {
 public:
  // Reads `path`: a .hgt, or a .zip with one .hgt inside (libzip). The
  // tile's corner comes from the file's name (the entry's, for a zip).
  void addFile(const std::string& path);
  void addTile(DemTile tile);

  bool empty() const { return tiles_.empty(); }
  const std::vector<DemTile>& tiles() const { return tiles_; }
  // Metres above the geoid at (lat, lon), bilinear between samples; NaN where
  // no tile covers the point.
  double height(double lat, double lon) const;
  // Throws core::Error (InvalidArg) naming each tile missing to cover the
  // box, e.g. "the DEM does not cover the city (43.72..43.75 N, 7.40..7.44 E):
  // no tile N43E008 (add N43E008.hgt)".
  void requireCovers(double lat_min, double lon_min, double lat_max, double lon_max) const;

 private:
  const DemTile* tileAt(int lat0, int lon0) const;
  std::vector<DemTile> tiles_;
};

}  // namespace blvd::bake
