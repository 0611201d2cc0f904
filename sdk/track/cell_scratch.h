// Per-cell scratch of a bounded search: a fixed open-addressing table keyed by
// cell id and cleared in O(1) by a run stamp. The matcher's candidate and
// route searches touch a bounded number of cells, so their memory depends on
// those bounds and not on how many cells the city has.
//
// Linear probing over a power-of-two table at most half full; lookups and
// inserts are deterministic (no iteration over the table).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace blvd::track {

template <class V>
class CellScratch {
 public:
  // Holds up to `capacity` cells a run.
  explicit CellScratch(uint32_t capacity) : capacity_(capacity ? capacity : 1) {
    uint32_t n = 2, bits = 1;
    while (n < 2 * capacity_) n *= 2, ++bits;
    slots_.resize(n);
    mask_ = n - 1;
    shift_ = 32 - bits;
  }

  // Forgets every cell (a new run).
  void clear() {
    used_ = 0;
    if (++stamp_ != 0) return;
    for (Slot& s : slots_) s.stamp = 0;
    stamp_ = 1;
  }

  V* find(uint32_t cell) {
    for (uint32_t i = hash(cell);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.stamp != stamp_) return nullptr;
      if (s.key == cell) return &s.value;
    }
  }

  // The cell's value, value-initialised when `fresh`; nullptr when the run
  // already holds `capacity` cells.
  V* insert(uint32_t cell, bool* fresh) {
    for (uint32_t i = hash(cell);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.stamp == stamp_) {
        if (s.key != cell) continue;
        *fresh = false;
        return &s.value;
      }
      if (used_ == capacity_) return nullptr;
      ++used_;
      s.stamp = stamp_;
      s.key = cell;
      s.value = V{};
      *fresh = true;
      return &s.value;
    }
  }

  uint32_t capacity() const { return capacity_; }
  size_t bytes() const { return slots_.capacity() * sizeof(Slot); }

 private:
  struct Slot {
    uint32_t stamp = 0;
    uint32_t key = 0;
    V value{};
  };
  uint32_t hash(uint32_t cell) const { return (cell * 0x9E3779B1u) >> shift_; }  // Fibonacci hashing

  std::vector<Slot> slots_;
  uint32_t mask_ = 0, shift_ = 31, stamp_ = 1, used_ = 0, capacity_;
};

}  // namespace blvd::track
