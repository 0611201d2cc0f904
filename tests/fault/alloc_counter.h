// Counts global operator new calls while an AllocCounter is alive, to check
// (shared by the tests of every module: tests/fault is the home of allocation checks)
// "no heap allocation" claims. The replacement operators live in
// alloc_counter.cpp (their own translation unit, so the compiler never sees a
// malloc'd pointer reach a sized delete it inlined).
#pragma once

namespace blvd_test {

class AllocCounter {
 public:
  AllocCounter();
  ~AllocCounter();
  AllocCounter(const AllocCounter&) = delete;
  AllocCounter& operator=(const AllocCounter&) = delete;
  long count() const;
};

}  // namespace blvd_test
