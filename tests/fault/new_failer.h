// Makes the n-th global operator new on this thread throw std::bad_alloc while
// a NewFailer is alive: every C++ allocation of a call can be failed in turn.
// Allocations made inside the GL driver (libLLVM, Mesa's libraries: found by
// the call stack, as sdk/cli/malloc_probe does) are never failed nor counted:
// the driver is built without exceptions and would abort, and its memory is
// not blvd's to account for. The replacement operators live in alloc_counter.cpp.
#pragma once

namespace blvd_test {

class NewFailer {
 public:
  // fail_at < 0: count only.
  explicit NewFailer(long fail_at);
  ~NewFailer();
  NewFailer(const NewFailer&) = delete;
  NewFailer& operator=(const NewFailer&) = delete;
  long count() const;   // blvd's operator new calls on this thread so far
  bool failed() const;  // the fail_at-th came
};

}  // namespace blvd_test
