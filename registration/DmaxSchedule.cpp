#include "registration/DmaxSchedule.hpp"

#include <algorithm>
#include <cmath>

namespace rovermap::registration {

const char* ToString(DmaxBranch branch) {
  switch (branch) {
    case DmaxBranch::kVeryGood: return "very_good";
    case DmaxBranch::kGood: return "good";
    case DmaxBranch::kAcceptable: return "acceptable";
    case DmaxBranch::kPoorValley: return "poor_valley";
    case DmaxBranch::kPoorKeep: return "poor_keep";
    case DmaxBranch::kNoPairs: return "no_pairs";
  }
  return "unknown";
}

bool FindHistogramValley(const std::vector<double>& distances, int bins, double valley_ratio,
                         double* xi_m) {
  if (distances.empty() || bins < 2) return false;
  const double max_d = *std::max_element(distances.begin(), distances.end());
  if (!(max_d > 0.0)) return false;
  const double width = max_d / bins;
  std::vector<int> counts(static_cast<std::size_t>(bins), 0);
  for (double d : distances) {
    const int b = std::min(bins - 1, static_cast<int>(d / width));
    ++counts[static_cast<std::size_t>(std::max(0, b))];
  }
  const auto peak_it = std::max_element(counts.begin(), counts.end());
  const int peak = static_cast<int>(peak_it - counts.begin());
  // Walk down from the peak to the first bin after which the count stops falling.
  int valley = peak;
  while (valley + 1 < bins && counts[valley + 1] < counts[valley]) ++valley;
  // A valley needs a rise somewhere after it; a tail that only falls or stays flat has none.
  const bool rises_after =
      std::any_of(counts.begin() + valley + 1, counts.end(), [&](int c) { return c > counts[valley]; });
  if (valley == peak || !rises_after) return false;
  if (counts[valley] > valley_ratio * *peak_it) return false;
  *xi_m = (valley + 1) * width;
  return true;
}

DmaxUpdate UpdateDmax(const std::vector<double>& distances, double reference_distance_m,
                      double previous_dmax_m, int histogram_bins, double valley_ratio) {
  DmaxUpdate out;
  out.dmax_m = previous_dmax_m;
  if (distances.empty()) return out;

  double sum = 0.0;
  for (double d : distances) sum += d;
  const double n = static_cast<double>(distances.size());
  out.mean_m = sum / n;
  double var = 0.0;
  for (double d : distances) var += (d - out.mean_m) * (d - out.mean_m);
  out.stddev_m = std::sqrt(var / n);

  const double mu = out.mean_m, sigma = out.stddev_m, d_ref = reference_distance_m;
  double candidate = previous_dmax_m;
  if (mu < d_ref) {
    out.branch = DmaxBranch::kVeryGood;
    candidate = mu + 3.0 * sigma;
  } else if (mu < 3.0 * d_ref) {
    out.branch = DmaxBranch::kGood;
    candidate = mu + 2.0 * sigma;
  } else if (mu < 6.0 * d_ref) {
    out.branch = DmaxBranch::kAcceptable;
    candidate = mu + sigma;
  } else {
    double xi = 0.0;
    if (FindHistogramValley(distances, histogram_bins, valley_ratio, &xi)) {
      out.branch = DmaxBranch::kPoorValley;
      candidate = xi;
    } else {
      out.branch = DmaxBranch::kPoorKeep;
    }
  }
  // Non-increasing Dmax (§4.3): the bound on the mean squared error then decreases.
  out.clamped = candidate > previous_dmax_m;
  out.dmax_m = std::min(candidate, previous_dmax_m);
  return out;
}

}  // namespace rovermap::registration
