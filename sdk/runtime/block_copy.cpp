// Block reuse: the local blocks a new cell shares with a resident one are
// copied from that slot's slab GPU to GPU instead of decoded again
// (cell_slots.h; blvd_runtime_desc.block_reuse).
#include "runtime/cell_slots.h"

namespace blvd::runtime {

// The blocks of `cell` that another resident slot than `victim` holds
// whole: into `copies` and their ids into `skip` (at most kMaxSkippedBlocks).
uint32_t CellSlots::sharedBlocks(uint32_t cell, uint32_t victim, std::vector<BlockCopy>& copies, uint32_t* skip) const {
  copies.clear();
  if (!block_reuse_) return 0;
  for (const uint32_t b : city_.streets().localBlocks(cell)) {
    if (copies.size() >= copies.capacity()) break;  // reserved for min(max local blocks, kMaxSkippedBlocks): the rest decode
    for (uint32_t i = 0; i < slots_.size(); ++i) {
      if (i == victim || slots_[i].state != CellSlot::Resident) continue;
      bool has = false;
      for (const SlotBlock& sb : slots_[i].blocks) has |= sb.block == b;
      if (!has) continue;
      skip[copies.size()] = b;
      copies.push_back(BlockCopy{b, i});
      break;
    }
  }
  return static_cast<uint32_t>(copies.size());
}

// The copies come after the staged meshes so that each block's levels stay
// together in slot.blocks: a level at a time in chunks of kUploadChunk,
// within the frame's upload budget (`spent` so far since t0) like an upload.
void CellSlots::copySharedBlocks(std::chrono::steady_clock::time_point t0, double budget_ms, double& spent) {
  for (CellSlot& slot : slots_) {
    if (slot.state != CellSlot::Loading || !slot.staged || slot.copies_done >= slot.copies.size()) continue;
    if (pending_copy_.slab && pending_copy_.slab != slot.slab.id) continue;  // another slot's copy is open
    while (slot.copies_done < slot.copies.size()) {
      const BlockCopy& c = slot.copies[slot.copies_done];
      const SlotBlock* src = nullptr;
      for (const SlotBlock& sb : slots_[c.from].blocks)
        if (sb.block == c.block) src = &sb;
      if (!slot.copy_open) {
        slot.blocks.push_back(SlotBlock{c.block, src ? src->levels : 0, {}});
        slot.copy_open = true;
      }
      if (!copyLevels(slot, src, t0, budget_ms, spent)) return;
      --slots_[c.from].copy_refs;
      ++counters_.blocks_reused;
      ++slot.copies_done;
      slot.copy_level = 0;
      slot.copy_open = false;
    }
    finishSlot(slot);
  }
}

// Copies `src`'s levels from slot.copy_level on into the slot's last block;
// false when the budget ran out first.
bool CellSlots::copyLevels(CellSlot& slot, const SlotBlock* src, std::chrono::steady_clock::time_point t0,
                           double budget_ms, double& spent) {
  SlotBlock& dst = slot.blocks.back();
  while (src && slot.copy_level < src->levels) {
    const render::MeshHandle from = src->lod[slot.copy_level];
    if (from.id == 0) {  // a level that decoded to nothing
      ++slot.copy_level;
      continue;
    }
    bool finished = true;
    render::MeshHandle h;
    if (pending_copy_.slab || renderer_.beginSlabCopy(slot.slab, from, pending_copy_))
      h = renderer_.continueSlabUpload(pending_copy_, kUploadChunk, finished);
    spent = msSince(t0);
    if (!finished) {
      if (spent >= budget_ms) return false;
      continue;
    }
    pending_copy_ = render::SlabUpload{};
    if (h.id == 0) {
      // The source is protected (copy_refs) and the slab sized for the
      // largest cell: this is a bug.
      last_error_ = "cell " + std::to_string(slot.cell) + ": block " + std::to_string(dst.block) +
                    " copy: " + renderer_.lastError();
      ++counters_.load_errors;
    } else {
      dst.lod[slot.copy_level] = h;
      ++counters_.block_levels_copied;
    }
    ++slot.copy_level;
    if (spent >= budget_ms) return false;
  }
  return true;
}

// Gives back the copy sources' references of a slot's pending copies.
void CellSlots::dropCopies(CellSlot& slot) {
  for (uint32_t i = slot.copies_done; i < slot.copies.size(); ++i) --slots_[slot.copies[i].from].copy_refs;
  if (pending_copy_.slab == slot.slab.id) pending_copy_ = render::SlabUpload{};
  slot.copies.clear();
  slot.copies_done = slot.copy_level = 0;
  slot.copy_open = false;
  slot.staged = false;
}

}  // namespace blvd::runtime
