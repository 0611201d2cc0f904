// Per-cell data the bake computes beyond the graph: the potentially visible
// set with coverage hints (PVSA section: Décoret 99 §5.3 item buffers, Marvie's
// Average Coverage Hints) and the impostor layers (IMPO section: one textured
// depth mesh per layer, Sillion 97 §4.2 / Décoret 99 §4).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/bytes.h"

namespace blvd::graph {

struct CellVisibility {
  std::vector<uint32_t> blocks;  // blocks seen from the cell (local ones included), ascending
  std::vector<float> ach;        // per block: mean pixel share over the cell's samples × 6 directions
};

struct ImpostorLayer {
  uint32_t blob = 0;             // GLB with the textured depth mesh and its texture
  uint32_t triangles = 0;        // exactly what decoding the blob gives
  uint32_t vertices = 0;         // exactly what decoding gives (the mesh has no normals: 3 per triangle)
  uint16_t texture_width = 0, texture_height = 0;  // of the image in the GLB; RGBA8 takes w × h × 4 bytes
  std::vector<uint32_t> blocks;  // the far blocks it stands for (never drawn with it, K06 §3.1.2)
  // The run of the cell it serves: drawn while the viewer's arc length along
  // the cell is at least this and below the next run's start (a long or
  // bending cell has several vantage points; docs/decisions/0010).
  float run_from_m = 0.f;
};

struct CellImpostors {
  std::vector<ImpostorLayer> layered;  // multi-layer impostor (D99), may be empty
  std::vector<ImpostorLayer> single;   // one mesh for all far blocks (S97), 0 or 1 entries
};

struct CellTables {
  std::vector<CellVisibility> visibility;  // per cell, or empty if not baked
  std::vector<CellImpostors> impostors;    // per cell, or empty if not baked
  float threshold_px = 0;                  // D99 layer threshold T used
  float display_fov_y_deg = 0;
  uint16_t display_width = 0, display_height = 0;
};

// `offsets` (optional) receives each cell's record offset in the section,
// for the cell table index.
std::vector<uint8_t> serializeVisibility(const CellTables& t, std::vector<uint64_t>* offsets = nullptr);
std::vector<uint8_t> serializeImpostors(const CellTables& t, std::vector<uint64_t>* offsets = nullptr);

// The CTIX section (package 3.1): per cell, where its PVSA and IMPO records
// start, so that a runtime reads one cell's tables without holding them all
// (docs/package-format.md has the layout).
constexpr uint32_t kCellTableIndexVersion = 1;
constexpr size_t kCellTableIndexHeader = 8, kCellTableIndexEntry = 16;
std::vector<uint8_t> serializeCellTableIndex(const std::vector<uint64_t>& visibility,
                                             const std::vector<uint64_t>& impostors);
// Throw core::Error(Corrupt) naming the section and offset; every index is
// checked against cells / blocks / blobs.
void parseVisibility(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t cells, uint32_t blocks,
                     CellTables& t);
// `lengths`: per cell its length (metres); a layer's run_from_m must lie in
// [0, length] and not decrease along the cell's list.
void parseImpostors(const uint8_t* data, size_t size, uint64_t file_offset, const std::vector<float>& lengths,
                    uint32_t blocks, uint32_t blobs, CellTables& t);

// The same a cell at a time, for a reader that checks a section without
// keeping it: the section's header, then each cell's record in turn (with
// the checks above); they throw core::Error(Corrupt) naming the offset.
void parseVisibilityHeader(core::ByteReader& r, uint32_t cells);
void parseCellVisibility(core::ByteReader& r, uint32_t blocks, CellVisibility& out);
void parseImpostorsHeader(core::ByteReader& r, uint32_t cells, CellTables& t);  // fills the display fields
void parseCellImpostors(core::ByteReader& r, uint32_t blocks, uint32_t blobs, float length, CellImpostors& out);

}  // namespace blvd::graph
