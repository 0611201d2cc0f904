// blvd_last_error(NULL): the reason the last create call on this thread failed
// (blvd_runtime_create, blvd_can_profile_create), shared by the capi files.
#pragma once
#include <string>

namespace blvd::capi {
extern thread_local std::string t_create_error;
}  // namespace blvd::capi
