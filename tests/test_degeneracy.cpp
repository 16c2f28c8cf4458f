// Per-direction fallback: the registration is kept in the directions its information
// constrains and the prediction in the others, with the covariance to match.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "mapper/Degeneracy.hpp"

using namespace rovermap::mapper;

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

Eigen::Isometry3d Pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (rotation_vector.norm() > 0)
    T.linear() =
        Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

Eigen::Vector3d RotationVector(const Eigen::Isometry3d& T) {
  const Eigen::AngleAxisd aa(T.linear());
  return aa.angle() * aa.axis();
}

// Information of point-to-plane pairs on the plane z = 0 (normals +z), points spread over
// ±`half` m: constrains z, roll and pitch only.
Matrix6d PlaneInformation(double half) {
  Matrix6d info = Matrix6d::Zero();
  for (double x = -half; x <= half; x += 0.5) {
    for (double y = -half; y <= half; y += 0.5) {
      const Eigen::Vector3d p(x, y, 0.0), n(0, 0, 1);
      Eigen::Matrix<double, 1, 6> j;
      j << p.cross(n).transpose(), n.transpose();  // n·(δr × p + δt)
      info += j.transpose() * j / 1e-4;
    }
  }
  return info;
}

Matrix6d Diagonal(double rotation_sigma, double translation_sigma) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(rotation_sigma * rotation_sigma),
      Eigen::Vector3d::Constant(translation_sigma * translation_sigma);
  return c;
}

}  // namespace

TEST(Degeneracy, DirectionNamesInFixedOrder) {
  EXPECT_EQ(DirectionNames(0), "");
  EXPECT_EQ(DirectionNames(kX | kY | kYaw), "yaw x y");
  EXPECT_EQ(DirectionNames(kRoll | kPitch | kYaw | kX | kY | kZ), "roll pitch yaw x y z");
}

TEST(Degeneracy, PlaneKeepsPredictionInXYYawAndRegistrationInZRollPitch) {
  const Eigen::Isometry3d predicted = Pose({0, 0, 0.02}, {0.5, 0.0, 0.0});
  // The registration moved every direction; on a plane only z, roll and pitch are trustworthy.
  const Eigen::Isometry3d registered = Pose({0.01, -0.008, 0.05}, {0.6, 0.05, 0.03});
  const BlendedIncrement b =
      BlendIncrement(predicted, registered, PlaneInformation(5.0), 5.0, 1e-3, Diagonal(0.01, 0.02));
  EXPECT_EQ(b.odometry_directions, kYaw | kX | kY) << DirectionNames(b.odometry_directions);
  EXPECT_EQ(b.constrained, 3);
  EXPECT_LT(b.min_ratio, 1e-12);
  // x, y and yaw as predicted (to first order in the small rotations), z, roll, pitch as
  // registered.
  const Eigen::Isometry3d D = b.T * predicted.inverse();
  const Eigen::Vector3d dr = RotationVector(D);
  const Eigen::Isometry3d R = registered * predicted.inverse();
  const Eigen::Vector3d rr = RotationVector(R);
  EXPECT_NEAR(dr.z(), 0.0, 1e-9);
  EXPECT_NEAR(D.translation().x(), 0.0, 1e-9);
  EXPECT_NEAR(D.translation().y(), 0.0, 1e-9);
  EXPECT_NEAR(dr.x(), rr.x(), 1e-9);
  EXPECT_NEAR(dr.y(), rr.y(), 1e-9);
  EXPECT_NEAR(D.translation().z(), R.translation().z(), 1e-9);
  // The covariance: odometry's in x, y, yaw; tiny (registration) in z, roll, pitch.
  EXPECT_NEAR(b.covariance(2, 2), 1e-4, 1e-9);
  EXPECT_NEAR(b.covariance(3, 3), 4e-4, 1e-9);
  EXPECT_NEAR(b.covariance(4, 4), 4e-4, 1e-9);
  EXPECT_LT(b.covariance(5, 5), 1e-6);
  EXPECT_LT(b.covariance(0, 0), 1e-6);
}

// The mapper chains the directions kept from dead reckoning with what it is typically wrong by
// (mapper.odometry_noise_*), not with the gates' bound: the projector must carry any prediction
// covariance onto exactly those directions, as `covariance` carries the bound.
TEST(Degeneracy, PredictionProjectorCarriesAnyPredictionCovarianceOntoTheKeptDirections) {
  const Eigen::Isometry3d predicted = Pose({0, 0, 0.02}, {0.5, 0.0, 0.0});
  const Eigen::Isometry3d registered = Pose({0.01, -0.008, 0.05}, {0.6, 0.05, 0.03});
  const Matrix6d bound = Diagonal(0.01, 0.02);
  const BlendedIncrement b =
      BlendIncrement(predicted, registered, PlaneInformation(5.0), 5.0, 1e-3, bound);
  const Matrix6d& P = b.prediction_projector;
  EXPECT_LT(
      (b.covariance_registered + P * bound * P.transpose() - b.covariance).cwiseAbs().maxCoeff(),
      1e-15);
  // A noise ten times smaller in σ: yaw, x and y a hundred times smaller in variance, the
  // registration's z, roll and pitch as they were.
  const Matrix6d noise = Diagonal(0.001, 0.002);
  const Matrix6d chained = b.covariance_registered + P * noise * P.transpose();
  EXPECT_NEAR(chained(2, 2), 1e-6, 1e-10);
  EXPECT_NEAR(chained(3, 3), 4e-6, 1e-10);
  EXPECT_NEAR(chained(4, 4), 4e-6, 1e-10);
  for (const int i : {0, 1, 5})
    EXPECT_NEAR(chained(i, i), b.covariance(i, i), 1e-6 * b.covariance(i, i)) << i;
  // Kept whole: nothing of the prediction; taken whole: all of it.
  Matrix6d full = PlaneInformation(5.0);
  full.topLeftCorner<3, 3>().diagonal() += Eigen::Vector3d::Constant(1e8);
  full.bottomRightCorner<3, 3>().diagonal() += Eigen::Vector3d::Constant(1e8);
  EXPECT_TRUE(BlendIncrement(predicted, registered, full, 5.0, 1e-3, bound)
                  .prediction_projector.isZero(1e-12));
  EXPECT_EQ(BlendIncrement(predicted, registered, Matrix6d::Zero(), 5.0, 1e-3, bound)
                .prediction_projector,
            Matrix6d::Identity());
}

TEST(Degeneracy, FullRankInformationKeepsTheRegistrationWhole) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d a;
  for (int i = 0; i < 36; ++i) a(i) = n(rng);
  const Matrix6d info = a * a.transpose() + Matrix6d::Identity() * 10.0;
  const Eigen::Isometry3d predicted = Pose({0.01, 0.02, 0.1}, {0.3, -0.1, 0.02});
  const Eigen::Isometry3d registered = Pose({0.012, 0.018, 0.12}, {0.31, -0.09, 0.025});
  const BlendedIncrement b =
      BlendIncrement(predicted, registered, info, 3.0, 1e-6, Diagonal(0.01, 0.02));
  EXPECT_EQ(b.odometry_directions, 0u);
  EXPECT_EQ(b.constrained, 6);
  EXPECT_LT((b.T.matrix() - registered.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // Covariance = information⁻¹.
  EXPECT_LT((b.covariance - info.inverse()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Degeneracy, ZeroInformationKeepsThePredictionWhole) {
  const Eigen::Isometry3d predicted = Pose({0, 0, 0.02}, {0.5, 0, 0});
  const Eigen::Isometry3d registered = Pose({0, 0, 0.03}, {0.55, 0.01, 0});
  const BlendedIncrement none =
      BlendIncrement(predicted, registered, Matrix6d::Zero(), 5.0, 1e-3, Diagonal(0.01, 0.02));
  EXPECT_EQ(none.constrained, 0);
  EXPECT_LT((none.T.matrix() - predicted.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(none.covariance, Diagonal(0.01, 0.02));
}

// Dead reckoning's bias: the directions kept from dead reckoning move by the bias estimate;
// the directions that inform it (here yaw, weak but above bias_min_information) say how far
// the registration's correction is from that estimate; uninformed ones (x, y) say nothing.
TEST(Degeneracy, UnconstrainedDirectionsTakeTheBiasAndInformedOnesUpdateIt) {
  const double extent = 5.0;
  Matrix6d info = PlaneInformation(extent);
  // A weak yaw constraint: 1e-5 of the largest scaled eigenvalue, as on gently rolling ground.
  const Eigen::SelfAdjointEigenSolver<Matrix6d> plane(info);
  const double largest_scaled = plane.eigenvalues()(5) / (extent * extent);
  info(2, 2) += 1e-5 * largest_scaled * extent * extent;
  const Eigen::Isometry3d predicted = Pose({0, 0, 0.02}, {0.5, 0.0, 0.0});
  const Eigen::Isometry3d registered = Pose({0.01, -0.008, 0.05}, {0.6, 0.05, 0.03});
  Vector6d bias;
  bias << 0.0, 0.0, 0.004, 0.01, -0.005, 0.0;
  const Matrix6d odometry = Diagonal(0.05, 0.2);
  const BlendedIncrement b =
      BlendIncrement(predicted, registered, info, extent, 1e-4, odometry, bias, 1e-6);
  EXPECT_EQ(b.odometry_directions, kYaw | kX | kY) << DirectionNames(b.odometry_directions);

  // x, y, yaw: the prediction moved by the bias (to first order); z, roll, pitch registered.
  const Eigen::Isometry3d D = b.T * predicted.inverse();
  const Eigen::Vector3d dr = RotationVector(D);
  const Eigen::Isometry3d R = registered * predicted.inverse();
  const Eigen::Vector3d rr = RotationVector(R);
  EXPECT_NEAR(dr.z(), 0.004, 1e-4);
  EXPECT_NEAR(D.translation().x(), 0.01, 1e-4);
  EXPECT_NEAR(D.translation().y(), -0.005, 1e-4);
  EXPECT_NEAR(dr.x(), rr.x(), 1e-4);
  EXPECT_NEAR(D.translation().z(), R.translation().z(), 1e-4);

  // What the frame tells of the bias: yaw's and z's corrections (informed), nothing in x and y
  // (no information); the registration's information in the informed directions, unscaled.
  EXPECT_NEAR(b.bias_correction(2), rr.z(), 1e-4);
  EXPECT_NEAR(b.bias_correction(3), 0.0, 1e-12);
  EXPECT_NEAR(b.bias_correction(4), 0.0, 1e-12);
  EXPECT_NEAR(b.bias_correction(5), R.translation().z(), 1e-4);
  EXPECT_NEAR(b.bias_information(2, 2), info(2, 2), 1e-9 * info(2, 2));
  EXPECT_LT(b.bias_information.row(3).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(b.bias_information.row(4).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((b.bias_information.bottomRightCorner<1, 1>() - info.bottomRightCorner<1, 1>())
                .cwiseAbs()
                .maxCoeff(),
            1e-9 * info(5, 5));

  // With the floor above yaw's information, yaw no longer informs the bias.
  const BlendedIncrement above =
      BlendIncrement(predicted, registered, info, extent, 1e-4, odometry, bias, 1e-4);
  EXPECT_NEAR(above.bias_correction(2), 0.0, 1e-12);
  EXPECT_LT(above.bias_information.row(2).cwiseAbs().maxCoeff(), 1e-9 * info(2, 2));
  // A correction beyond 3σ of dead reckoning's error model informs nothing.
  const BlendedIncrement implausible =
      BlendIncrement(predicted, registered, info, extent, 1e-4, Diagonal(0.001, 0.001), bias, 1e-6);
  EXPECT_EQ(implausible.bias_correction, Vector6d::Zero());
  EXPECT_EQ(implausible.bias_information, Matrix6d::Zero());
  // Without a bias the unconstrained directions are the prediction's, as before.
  const BlendedIncrement none = BlendIncrement(predicted, registered, info, extent, 1e-4, odometry);
  EXPECT_NEAR((none.T * predicted.inverse()).translation().x(), 0.0, 1e-9);
}
