#pragma once

#include <vector>

namespace rovermap::registration {

/// Which branch of Zhang's threshold update was taken (1994, §4.3).
enum class DmaxBranch {
  kVeryGood,    ///< μ < D:  Dmax = μ + 3σ
  kGood,        ///< μ < 3D: Dmax = μ + 2σ
  kAcceptable,  ///< μ < 6D: Dmax = μ + σ
  kPoorValley,  ///< otherwise, histogram valley ξ found
  kPoorKeep,    ///< otherwise, no valley deep enough: previous Dmax kept
  kNoPairs,     ///< no distances: previous Dmax kept
};

const char* ToString(DmaxBranch branch);

struct DmaxUpdate {
  double dmax_m = 0.0;
  DmaxBranch branch = DmaxBranch::kNoPairs;
  double mean_m = 0.0;    ///< μ of the distances
  double stddev_m = 0.0;  ///< σ of the distances
  bool clamped = false;   ///< the candidate exceeded the previous Dmax and was clamped to it
};

/// Adaptive maximum distance (Zhang 1994, §4.3). `distances` are the closest-point
/// distances of the pairs found within `previous_dmax_m`. The result never exceeds
/// `previous_dmax_m` (non-increasing, so the bound on the mean squared error decreases).
DmaxUpdate UpdateDmax(const std::vector<double>& distances, double reference_distance_m,
                      double previous_dmax_m, int histogram_bins = 20,
                      double valley_ratio = 0.6);

/// ξ: the distance at the valley following the highest peak of the histogram of
/// `distances` over [0, max] in `bins` bins, if the valley's count is at most
/// `valley_ratio` times the peak's. The valley is the bin where the count first stops
/// falling after the peak, and some later bin must rise above it; ξ is the valley bin's
/// upper edge (the pairs of the valley bin are kept).
/// @return false if there is no such valley (a tail that never rises, or too shallow).
bool FindHistogramValley(const std::vector<double>& distances, int bins, double valley_ratio,
                         double* xi_m);

}  // namespace rovermap::registration
