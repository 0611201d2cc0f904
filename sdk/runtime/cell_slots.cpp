#include "runtime/cell_slots.h"

#include <algorithm>

#include "core/status.h"

namespace blvd::runtime {

CellSlots::CellSlots(const stream::City& city, render::Renderer& renderer, CellLoader& loader, const MemoryPlan& plan,
                     bool block_reuse)
    : city_(city), renderer_(renderer), loader_(loader), plan_(plan), block_reuse_(block_reuse) {
  slots_.resize(plan.resident_cells);
  slot_cells_.assign(plan.resident_cells, graph::kNone);
  const size_t copies = std::min<size_t>(plan.max_local_blocks, kMaxSkippedBlocks);
  for (CellSlot& slot : slots_) {
    slot.slab = renderer.createSlab(plan.slab);
    if (slot.slab.id == 0)
      throw core::Error(renderer.outOfMemory() ? core::Status::NoMem : core::Status::Backend,
                        "cell slab: " + renderer.lastError());
    slot.blocks.reserve(plan.max_local_blocks);
    slot.copies.reserve(copies);
    slot.layered.reserve(plan.max_cell_layers);
    slot.single.reserve(plan.max_cell_layers);
    slot.layers.resize(plan.max_cell_layers);
  }
  failed_cells_.assign(8, graph::kNone);
  copy_sources_ = std::make_unique<bool[]>(plan.resident_cells);
  copy_scratch_.reserve(copies);
}

void CellSlots::releaseAll() {
  for (CellSlot& slot : slots_) renderer_.resetSlab(slot.slab);
}

const CellSlot* CellSlots::resident(uint32_t cell) const {
  for (const CellSlot& s : slots_)
    if (s.state == CellSlot::Resident && s.cell == cell) return &s;
  return nullptr;
}

uint32_t CellSlots::residentCount() const {
  uint32_t n = 0;
  for (const CellSlot& s : slots_) n += s.state == CellSlot::Resident;
  return n;
}

uint64_t CellSlots::usedBytes() const {
  uint64_t used = 0;
  for (const CellSlot& s : slots_) used += s.bytes;
  return used;
}

void CellSlots::empty(size_t i) {
  dropCopies(slots_[i]);
  slots_[i].state = CellSlot::Empty;
  slots_[i].cell = slot_cells_[i] = graph::kNone;
}

// Residency for this frame: ask for what is wanted, most wanted
// first, into free or releasable slots; never wait for a load.
void CellSlots::stream(stream::Residency& residency, uint32_t cell, double arc_m, double speed_mps,
                       double upload_budget_ms) {
  residency.update({cell, arc_m, speed_mps});
  // A slot whose request was dropped goes back to empty (one copying its
  // shared blocks has no request left, and keeps going).
  for (size_t i = 0; i < slots_.size(); ++i)
    if (slots_[i].state == CellSlot::Loading && !slots_[i].staged && !loader_.pending(slots_[i].cell)) empty(i);
  // The current cell jumps the queue: queued predictions make way for it, or
  // its own queued prediction moves to the normal-priority thread.
  if (cell != graph::kNone && !resident(cell)) {
    if (loader_.pending(cell)) loader_.promote(cell);
    else loader_.cancelQueued();
  }
  request(residency, cell);
  pinWanted(residency);
  uploadStaged(upload_budget_ms);
}

// Requests the wanted cells no slot holds, into Residency's victims, until
// the loader's staging is busy or nothing may go.
void CellSlots::request(stream::Residency& residency, uint32_t cell) {
  for (uint32_t r = 0; r < residency.wantedCount(); ++r) {
    const uint32_t c = residency.wanted()[r];
    bool have = false;
    for (const CellSlot& s : slots_) have |= s.cell == c && s.state != CellSlot::Empty;
    if (have || failed(c)) continue;
    if (!mayFetch(c, r)) continue;
    // A slot that shared blocks are being copied from stays.
    for (size_t i = 0; i < slots_.size(); ++i) copy_sources_[i] = slots_[i].copy_refs > 0;
    const uint32_t v = residency.victim(slot_cells_.data(), slot_cells_.size(), r, copy_sources_.get());
    if (v == graph::kNone) break;
    uint32_t shared;
    try {
      shared = sharedBlocks(c, v, copy_scratch_, skip_scratch_);
    } catch (const core::Error& e) {
      if (e.status() != core::Status::Unavailable) throw;
      continue;  // its table pages are on their way over the link: asked for again next frame
    }
    if (!loader_.request(c, v, c == cell, skip_scratch_, shared)) break;  // both staging arenas busy
    CellSlot& slot = slots_[v];
    if (slot.cell != graph::kNone) ++counters_.evictions;
    dropCopies(slot);
    renderer_.resetSlab(slot.slab);
    slot.blocks.clear();
    slot.layered.clear();
    slot.single.clear();
    slot.bytes = 0;
    slot.state = CellSlot::Loading;
    slot.cell = slot_cells_[v] = c;
    for (const BlockCopy& bc : copy_scratch_) {
      slot.copies.push_back(bc);
      ++slots_[bc.from].copy_refs;
    }
  }
}

}  // namespace blvd::runtime
