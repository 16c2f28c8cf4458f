#pragma once
// The label of an axis or colour-bar tick, shared by dem.png and the eval and drift plots.
// Header-only: a formatting rule, no state.

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace rovermap::io {

/// `value` with as many decimals as `step` (the distance between ticks) needs: "1000" for a
/// step of 100, "0.25" for 0.05. A value within a millionth of a step of zero prints as zero,
/// never "-0.0". The guard of 1e-9 keeps a step a rounding error below a power of ten (0.1 as
/// 0.09999999999999999) at that power's decimals.
inline std::string TickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  if (std::abs(value) < 1e-6 * step) value = 0.0;
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << value;
  return s.str();
}

}  // namespace rovermap::io
