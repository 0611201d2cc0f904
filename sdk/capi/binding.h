// What every file of the C binding shares: the handle behind blvd_runtime*,
// the last-error text of a failed create on this thread (blvd_last_error(NULL)),
// and `guarded`, the catch-all that turns an exception into a status so none
// crosses `extern "C"`.
#pragma once
#include <new>
#include <string>

#include "blvd/blvd.h"
#include "core/status.h"
#include "runtime/runtime.h"

struct blvd_runtime {
  blvd::runtime::Runtime* impl;
};

namespace blvd::capi {

extern thread_local std::string t_create_error;

inline blvd_status toStatus(core::Status s) { return static_cast<blvd_status>(static_cast<int>(s)); }

// Runs f, converting exceptions into a status and rt's last error (the
// create error when rt is NULL).
template <typename F>
blvd_status guarded(blvd_runtime* rt, F&& f) {
  std::string* err = rt ? &rt->impl->last_error : &t_create_error;
  try {
    f();
    return BLVD_OK;
  } catch (const core::Error& e) {
    *err = e.what();
    return toStatus(e.status());
  } catch (const std::bad_alloc&) {
    *err = "out of memory";
    return BLVD_ERR_NOMEM;
  } catch (const std::exception& e) {
    *err = std::string("internal error: ") + e.what();
    return BLVD_ERR_INTERNAL;
  } catch (...) {
    *err = "internal error: unknown exception";
    return BLVD_ERR_INTERNAL;
  }
}

// A NULL handle, or a call out of order.
inline blvd_status misuse(blvd_runtime* rt, const char* what) {
  (rt ? rt->impl->last_error : t_create_error) = what;
  return BLVD_ERR_MISUSE;
}

// A NULL pointer argument.
inline blvd_status nullArg(blvd_runtime* rt, const char* what) {
  (rt ? rt->impl->last_error : t_create_error) = what;
  return BLVD_ERR_INVALID_ARG;
}

}  // namespace blvd::capi
