// The constants of angle arithmetic, once for the SDK.
#pragma once

namespace blvd::core {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;

}  // namespace blvd::core
