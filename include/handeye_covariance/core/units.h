// Units: SI inside (m, rad, s); people read and type mm, degrees and ms. Every conversion
// between them is here, computed as the package always computed it inline (x * pi /
// 180, x * 180 / pi, x * 1e3, x * 1e-3), so a converted figure is the same to the bit.
// Numbers and Eigen vectors and matrices alike (Eigen's are evaluated).
#pragma once

#include <Eigen/Core>

namespace handeye {

constexpr double kPi = 3.14159265358979323846;

constexpr double degrees(double radians) { return radians * 180.0 / kPi; }
constexpr double radians(double degrees) { return degrees * kPi / 180.0; }
constexpr double millimetres(double metres) { return metres * 1e3; }
constexpr double metres(double millimetres) { return millimetres * 1e-3; }
constexpr double milliseconds(double seconds) { return seconds * 1e3; }

template <typename Derived>
auto degrees(const Eigen::MatrixBase<Derived>& radians) { return (radians * 180.0 / kPi).eval(); }
template <typename Derived>
auto millimetres(const Eigen::MatrixBase<Derived>& metres) { return (metres * 1e3).eval(); }

/// Scale factors, where a conversion is passed on (a per-axis printer's unit).
constexpr double kDegreesPerRadian = 180.0 / kPi, kRadiansPerDegree = kPi / 180.0;
constexpr double kMillimetresPerMetre = 1e3, kMetresPerMillimetre = 1e-3;

}  // namespace handeye
