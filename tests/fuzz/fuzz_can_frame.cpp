// Fuzz target for the C API's CAN path: blvd_can_profile_decode() on frames made
// of the input bytes (any id, flags, length, payload) with the Toyota, VW MQB
// and Hyundai profiles: a frame is decoded, ignored (BLVD_ERR_NOT_FOUND) or
// refused (BLVD_ERR_INVALID_ARG, exactly when its length or id cannot exist),
// never a crash; decoded odometry is finite.
//
// Input layout: 4 bytes id, 1 byte flags, 1 byte length, then the payload;
// repeated while bytes remain. Seeds: the target writes one frame of each
// profile message into BLVD_FUZZ_SEED_DIR.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "blvd/blvd.h"

namespace {

blvd_can_profile* g_profiles[3] = {};

const char* const kDbc[3] = {"toyota_new_mc_pt_generated.dbc", "vw_mqb.dbc", "hyundai_2015_ccan.dbc"};

void writeSeed(const std::filesystem::path& dir, const char* name, uint32_t id, uint8_t len) {
  std::ofstream f(dir / name, std::ios::binary);
  const uint8_t head[6] = {static_cast<uint8_t>(id), static_cast<uint8_t>(id >> 8), 0, 0, 0, len};
  f.write(reinterpret_cast<const char*>(head), sizeof head);
  for (uint8_t i = 0; i < len; ++i) f.put(static_cast<char>(0x11 * (i + 1)));
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  for (int v = 0; v < 3; ++v) {
    blvd_can_profile_desc d{};
    d.struct_size = sizeof d;
    d.vehicle = static_cast<blvd_vehicle>(v);
    const std::string path = std::string(BLVD_TEST_DATA_DIR) + "/can/dbc/" + kDbc[v];
    d.dbc_path = path.c_str();
    if (blvd_can_profile_create(&d, &g_profiles[v]) != BLVD_OK) std::abort();
  }
  const char* dir = std::getenv("BLVD_FUZZ_SEED_DIR");
  if (dir && *dir) {
    std::filesystem::create_directories(dir);
    writeSeed(dir, "toyota_wheels", 0xAA, 8);
    writeSeed(dir, "toyota_kinematics", 0x24, 8);
    writeSeed(dir, "vw_esp19", 0xB2, 8);
    writeSeed(dir, "hyundai_whl_spd11", 0x386, 8);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  size_t at = 0;
  while (size - at >= 6) {
    blvd_can_frame f{};
    f.struct_size = sizeof f;
    std::memcpy(&f.id, data + at, 4);
    f.flags = data[at + 4] & 0x0F;
    f.len = data[at + 5];
    at += 6;
    const size_t n = std::min<size_t>({f.len, sizeof f.data, size - at});
    std::memcpy(f.data, data + at, n);
    at += n;
    f.t = static_cast<double>(at);
    const bool fd = f.flags & BLVD_CAN_FD;
    const bool fd_len = f.len <= 8 || f.len == 12 || f.len == 16 || f.len == 20 || f.len == 24 || f.len == 32 ||
                        f.len == 48 || f.len == 64;
    const bool id_ok = (f.flags & BLVD_CAN_ERROR) || f.id <= ((f.flags & BLVD_CAN_EXTENDED) ? 0x1FFFFFFFu : 0x7FFu);
    const bool valid = (fd ? fd_len : f.len <= 8) && id_ok;
    for (blvd_can_profile* p : g_profiles) {
      blvd_odometry odo{};
      odo.struct_size = sizeof odo;
      const blvd_status st = blvd_can_profile_decode(p, &f, &odo);
      if (!valid) {
        if (st != BLVD_ERR_INVALID_ARG) std::abort();
        continue;
      }
      if (st == BLVD_ERR_NOT_FOUND) continue;
      if (st != BLVD_OK || odo.flags == 0) std::abort();
      if (!std::isfinite(odo.speed_mps) || !std::isfinite(odo.yaw_rate_dps)) std::abort();
    }
  }
  return 0;
}
