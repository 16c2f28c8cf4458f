#pragma once
// Angle units: configuration keys, reports and tables speak degrees, the maths radians.

namespace rovermap::core {

constexpr double kPi = 3.14159265358979323846;  // M_PI's value, without relying on POSIX
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;

}  // namespace rovermap::core
