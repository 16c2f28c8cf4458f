#include "registration/Anderson.hpp"

#include <Eigen/QR>

namespace rovermap::registration {

AndersonAccelerator::Vector6 AndersonAccelerator::Next(const Vector6& x, const Vector6& g) {
  if (depth_ <= 0) return g;
  g_history_.push_back(g);
  f_history_.push_back(g - x);
  while (static_cast<int>(g_history_.size()) > depth_ + 1) {
    g_history_.pop_front();
    f_history_.pop_front();
  }
  const int m = static_cast<int>(g_history_.size()) - 1;
  if (m < 1) return g;
  Eigen::Matrix<double, 6, Eigen::Dynamic> delta_f(6, m), delta_g(6, m);
  for (int j = 0; j < m; ++j) {
    delta_f.col(j) = f_history_[j + 1] - f_history_[j];
    delta_g.col(j) = g_history_[j + 1] - g_history_[j];
  }
  // Rank-revealing QR: nearly parallel past steps give a rank-deficient ΔF.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(delta_f);
  if (qr.rank() == 0) return g;
  const Eigen::VectorXd theta = qr.solve(f_history_.back());
  const Vector6 next = g - delta_g * theta;
  return next.allFinite() ? next : g;
}

void AndersonAccelerator::Reset() {
  g_history_.clear();
  f_history_.clear();
}

}  // namespace rovermap::registration
