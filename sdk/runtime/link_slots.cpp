// The cell slots' side of a package on a server: what may be fetched in the
// link's mode, what the disk cache keeps, and when an unavailable cell is
// asked for again. Nothing here runs for a local package.
#include <algorithm>

#include "runtime/cell_slots.h"

namespace blvd::runtime {
namespace {
constexpr std::chrono::seconds kLinkRetry{2};
}  // namespace

bool CellSlots::mayFetch(uint32_t cell, uint32_t r) {
  remote::RemotePackage* rp = city_.remote();
  if (!rp) return true;
  const auto now = std::chrono::steady_clock::now();
  for (const LinkWait& w : link_waits_)
    if (w.cell == cell && now < w.until) return false;
  const remote::LinkMode mode = rp->mode();
  if (mode == remote::LinkMode::Online || (mode == remote::LinkMode::Metered && r <= 1)) return true;
  return city_.cellCached(cell, blob_scratch_);
}

void CellSlots::pinWanted(const stream::Residency& residency) {
  remote::RemotePackage* rp = city_.remote();
  if (!rp) return;
  const uint32_t* w = residency.wanted();
  const size_t n = residency.wantedCount();
  if (pinned_cells_.size() == n && std::equal(w, w + n, pinned_cells_.begin())) return;
  pinned_cells_.assign(w, w + n);
  pin_scratch_.clear();
  for (const uint32_t c : pinned_cells_) {
    try {
      city_.cellBlobs(c, nullptr, 0, blob_scratch_);
    } catch (const core::Error&) {
      continue;  // its table pages are not there (offline): nothing of it is cached to keep
    }
    pin_scratch_.insert(pin_scratch_.end(), blob_scratch_.begin(), blob_scratch_.end());
  }
  rp->pin(pin_scratch_);
}

void CellSlots::waitForLink(uint32_t cell) {
  ++counters_.link_waits;
  link_waits_[link_wait_next_++ % std::size(link_waits_)] = {cell, std::chrono::steady_clock::now() + kLinkRetry};
}

}  // namespace blvd::runtime
