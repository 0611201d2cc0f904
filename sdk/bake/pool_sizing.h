// The package header's pool sizing fields (format 2.0): exact maxima over
// blocks and cells, computed from the BLCK records, the cells' local-block
// lists and the IMPO layers, so the runtime carves every pool at create from
// the header alone. docs/package-format.md defines each field.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/street_graph.h"
#include "package/format.h"

namespace blvd::bake {

// Fills max_block_blob_bytes, max_cell_blob_bytes, every max_block_* /
// max_cell_* / max_impostor_* field of `h` and the impostor atlas's size. `blob_bytes(i)` is blob i's size.
// Throws core::Error(Internal) when a sum does not fit its field.
void fillPoolSizing(const graph::StreetGraph& g, const std::vector<graph::BlockRecord>& blocks,
                    const graph::CellTables& tables, const std::function<uint64_t(uint32_t)>& blob_bytes,
                    package::PackageHeader& h);

}  // namespace blvd::bake
