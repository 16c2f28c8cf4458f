#pragma once

#include <Eigen/Core>
#include <deque>

namespace rovermap::registration {

/// Anderson acceleration (type II, Walker & Ni 2011) of a fixed-point iteration x ← G(x) in
/// R⁶, as in AA-ICP (Pavlov et al. 2018): ICP's update is such an iteration on the pose, and
/// it converges only linearly where a surface lets the clouds slide (docs/design.md §1,
/// "Known weakness"). The caller keeps the safeguard: an extrapolated pose is accepted only if it
/// does not raise the registration energy.
class AndersonAccelerator {
 public:
  using Vector6 = Eigen::Matrix<double, 6, 1>;

  /// `depth`: how many past steps are combined (m); 0 turns the extrapolation off.
  explicit AndersonAccelerator(int depth) : depth_(depth) {}

  /// Records x_k and g_k = G(x_k) and returns the next iterate: g_k − ΔG·θ with
  /// θ = argmin ‖f_k − ΔF·θ‖ (f = g − x, Δ over the last `depth` steps); g_k itself while the
  /// history is too short or the least-squares problem degenerates.
  Vector6 Next(const Vector6& x, const Vector6& g);

  /// Forgets the history (after a rejected extrapolation, or when the objective changes).
  void Reset();

 private:
  int depth_;
  std::deque<Vector6> g_history_;  // g_{k−m} … g_k
  std::deque<Vector6> f_history_;  // f_{k−m} … f_k
};

}  // namespace rovermap::registration
