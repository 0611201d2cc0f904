// Counts global operator new calls while an AllocCounter is alive, to check the
// "no heap allocation after construction" claims of sdk/track. The replacement
// operators live in alloc_counter.cpp, their own translation unit (the same
// scheme as tests/adapters/gnss).
#pragma once

namespace blvd_track_test {

class AllocCounter {
 public:
  AllocCounter();
  ~AllocCounter();
  AllocCounter(const AllocCounter&) = delete;
  AllocCounter& operator=(const AllocCounter&) = delete;
  long count() const;
};

}  // namespace blvd_track_test
