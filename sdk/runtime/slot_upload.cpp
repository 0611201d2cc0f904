// Staging -> slab: the loader's decoded meshes copied into a slot's GL slab
// within the frame's upload budget (cell_slots.h).
#include <algorithm>
#include <chrono>

#include "runtime/cell_slots.h"

namespace blvd::runtime {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Copies finished staging into its slab, a chunk of at most kUploadChunk
// bytes at a time (a buffer range, or texture rows), until the frame's upload
// budget is spent: a large block or impostor texture spreads over several
// frames instead of stalling one. At least one chunk a frame, so a load
// always ends.
void CellSlots::uploadStaged(double budget_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  double spent = 0;
  while (Staging* st = loader_.finished()) {
    CellSlot& slot = slots_[st->target];
    // Evicted while loading, or the second of a promoted request's two copies.
    if (slot.state != CellSlot::Loading || slot.cell != st->cell || slot.staged) {
      pending_upload_ = render::SlabUpload{};
      loader_.release(st);
      continue;
    }
    if (st->state == Staging::Failed && st->unavailable) {
      last_error_ = st->error;
      waitForLink(st->cell);
      const uint32_t target = st->target;
      loader_.release(st);
      empty(target);
      continue;
    }
    if (st->state == Staging::Failed) {
      last_error_ = st->error;
      ++counters_.load_errors;
      if (!st->out_of_memory) failed_cells_[failed_next_++ % failed_cells_.size()] = st->cell;  // else asked again
      const uint32_t target = st->target;
      loader_.release(st);
      empty(target);
      continue;
    }
    const bool done = uploadMeshes(slot, *st, t0, budget_ms, spent);
    if (done) {
      if (st->bad_blocks) {  // drawn without them
        counters_.load_errors += st->bad_blocks;
        last_error_ = st->error;
      }
      loader_.release(st);
      slot.staged = true;
      if (slot.copies_done >= slot.copies.size()) finishSlot(slot);
    }
    if (spent >= budget_ms) break;
  }
  if (spent < budget_ms) copySharedBlocks(t0, budget_ms, spent);
  counters_.upload_ms = msSince(t0);
  counters_.upload_ms_max = std::max(counters_.upload_ms_max, counters_.upload_ms);
}

// Uploads `st`'s meshes from the next one on, until all are in (true) or the
// budget is spent. A block's levels arrive together, finest first.
bool CellSlots::uploadMeshes(CellSlot& slot, Staging& st, std::chrono::steady_clock::time_point t0, double budget_ms,
                             double& spent) {
  while (st.uploaded < st.mesh_count) {
    const StagedMesh& m = st.meshes[st.uploaded];
    bool finished = true;
    render::MeshHandle h;
    if (pending_upload_.slab || renderer_.beginSlabUpload(slot.slab, m.mesh, pending_upload_))
      h = renderer_.continueSlabUpload(pending_upload_, kUploadChunk, finished);
    spent = msSince(t0);
    if (!finished) {
      if (spent >= budget_ms) return false;
      continue;
    }
    pending_upload_ = render::SlabUpload{};
    ++st.uploaded;
    if (h.id == 0) {
      // The plan sized the slab for the largest cell: this is a bug.
      last_error_ = "cell " + std::to_string(st.cell) + ": " + renderer_.lastError();
      ++counters_.load_errors;
      return st.uploaded >= st.mesh_count;
    }
    if (m.kind == MeshKind::Block) {
      if (slot.blocks.empty() || slot.blocks.back().block != m.item) slot.blocks.push_back(SlotBlock{m.item, 0, {}});
      SlotBlock& sb = slot.blocks.back();
      if (m.level < graph::kMaxBlockLods) {
        sb.lod[m.level] = h;
        sb.levels = std::max(sb.levels, m.level + 1);
      }
    } else {
      (m.kind == MeshKind::Layered ? slot.layered : slot.single).push_back(h);
    }
    if (spent >= budget_ms) return st.uploaded >= st.mesh_count;
  }
  return true;
}

void CellSlots::finishSlot(CellSlot& slot) {
  // The copied blocks came after the decoded ones: back into the cell's
  // order of local blocks, so that a cell draws (and shares its budget) the
  // same whichever way its blocks arrived. Block ids are unique in a slot.
  if (!slot.copies.empty()) {
    const graph::GraphSource::List local = city_.streets().localBlocks(slot.cell);
    auto order = [&](uint32_t block) {
      uint32_t i = 0;
      for (uint32_t b : local) {
        if (b == block) break;
        ++i;
      }
      return i;
    };
    std::sort(slot.blocks.begin(), slot.blocks.end(),
              [&](const SlotBlock& a, const SlotBlock& b) { return order(a.block) < order(b.block); });
  }
  // What drawing the cell reads of its tables: the impostor layers' runs and
  // the blocks' coverage hints, read once here rather than every frame.
  city_.cellLayers(slot.cell, slot.layers.data(), static_cast<uint32_t>(slot.layers.size()), &slot.layered_count,
                   &slot.single_count);
  for (SlotBlock& b : slot.blocks) b.ach = city_.coverage(slot.cell, b.block), b.record = city_.block(b.block);
  const render::SlabUsage u = renderer_.slabUsage(slot.slab);
  slot.bytes = u.vertex_bytes + u.index_bytes + u.texture_bytes;
  slot.state = CellSlot::Resident;
  high_water_ = std::max(high_water_, usedBytes());
}

}  // namespace blvd::runtime
