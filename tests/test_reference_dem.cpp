// A reference DEM (docs/graph.md): io::ReferenceDem places any GeoTIFF GDAL reads in the
// sequence's world frame, whatever its CRS, and refuses one it cannot place (no CRS, another
// body, no heights); mapper::MatchReference registers the rover's DEM onto it, finds a known
// misplacement within its stated σ, and refuses ground that does not fix the placement (a
// plane, ripples of one direction) or fixes it more than once (a periodic field).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "io/GeoTiff.hpp"
#include "io/Georeference.hpp"
#include "io/IoError.hpp"
#include "io/ReferenceDem.hpp"
#include "mapper/Patches.hpp"
#include "mapper/ReferenceMatch.hpp"
#include "mapper/Revisit.hpp"
#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

using Terrain = std::function<double(double, double)>;  // world (x, y) -> z

const io::Georeference& Georef() {
  static const io::Georeference g(io::GeodeticOrigin{46.5191, 6.5668, 400.0});
  return g;
}

// World (x, y) of projected (E, N) near the origin: the inverse of GridToProjected.
Eigen::Vector2d WorldOfProjected(double e, double n) {
  const io::Georeference& g = Georef();
  const Eigen::Vector2d grid = (Eigen::Vector2d(e, n) - g.origin_projected()) / g.scale_factor();
  return Eigen::Rotation2Dd(-g.convergence_rad()) * grid;
}

// Bumps of 2-6 m radius, up and down, on a gentle slope: craters' scale of relief.
Terrain Bumpy() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> x(-30, 80), y(-40, 40), r(2, 6), a(-1.2, 1.2);
  std::vector<Eigen::Vector4d> bumps;
  for (int k = 0; k < 300; ++k) bumps.emplace_back(x(rng), y(rng), r(rng), a(rng));
  return [bumps](double px, double py) {
    double z = 0.02 * px;
    for (const Eigen::Vector4d& b : bumps) {
      const double d2 = (px - b[0]) * (px - b[0]) + (py - b[1]) * (py - b[1]);
      z += b[3] * std::exp(-d2 / (2 * b[2] * b[2]));
    }
    return z;
  };
}

// A north-up 1 m/post reference of `terrain` in the sequence's UTM zone over world
// [-40, 100] x [-60, 60], heights above the origin's altitude (ELEVATION_DATUM, as rovermap
// writes its DEMs), with noise of `sigma_m` and that σ in band 2.
fs::path WriteUtmReference(const fs::path& path, const Terrain& terrain, double sigma_m) {
  const io::Georeference& g = Georef();
  io::RasterFrame frame;
  const double post = 1.0;
  frame.width = 140;
  frame.height = 120;
  const Eigen::Vector2d p0 = g.origin_projected();
  frame.geotransform = {std::floor(p0.x()) - 40.0, post, 0.0,
                        std::floor(p0.y()) + 60.0, 0.0,  -post};
  frame.wkt = g.wkt();
  frame.metadata = {{"ELEVATION_DATUM", "height above the origin altitude 400.000000 m"}};
  std::vector<float> z(static_cast<std::size_t>(frame.width) * frame.height);
  std::vector<float> s(z.size(), static_cast<float>(std::max(sigma_m, 1e-3)));
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, std::max(sigma_m, 1e-12));
  for (int row = 0; row < frame.height; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      const Eigen::Vector2d w = WorldOfProjected(frame.geotransform[0] + (col + 0.5) * post,
                                                 frame.geotransform[3] - (row + 0.5) * post);
      z[static_cast<std::size_t>(row) * frame.width + col] =
          static_cast<float>(terrain(w.x(), w.y()) + noise(rng));
    }
  }
  io::WriteFloatGeoTiff(path, frame, {{&z, "elevation", "m"}, {&s, "sigma", "m"}});
  return path;
}

// The same terrain in geographic coordinates (EPSG:4326, 1e-5 degree posts), ellipsoidal
// heights, one band.
fs::path WriteGeographicReference(const fs::path& path, const Terrain& terrain) {
  const io::Georeference& g = Georef();
  io::RasterFrame frame;
  frame.width = 120;
  frame.height = 100;
  const double step = 1e-5;
  const Eigen::Vector3d nw = g.EnuToGeodetic(-40.0, 50.0, 0.0);
  frame.geotransform = {nw.y(), step, 0.0, nw.x(), 0.0, -step};
  frame.wkt =
      "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],"
      "PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433],AUTHORITY[\"EPSG\",\"4326\"]]";
  std::vector<float> z(static_cast<std::size_t>(frame.width) * frame.height);
  for (int row = 0; row < frame.height; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      const double lon = frame.geotransform[0] + (col + 0.5) * step;
      const double lat = frame.geotransform[3] - (row + 0.5) * step;
      const Eigen::Vector3d w = g.GeodeticToEnu(lat, lon, 400.0);
      // Ellipsoidal height of the terrain: world z plus the origin's altitude (the plane's drop
      // over 100 m, 1 mm, is left to the tolerance).
      z[static_cast<std::size_t>(row) * frame.width + col] =
          static_cast<float>(terrain(w.x(), w.y()) + 400.0);
    }
  }
  io::WriteFloatGeoTiff(path, frame, {{&z, "elevation", "m"}});
  return path;
}

class ReferenceDemTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = rovermap::testing::ScratchDir(); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

// The same plane in UTM and in geographic coordinates comes out at the same world heights.
TEST_F(ReferenceDemTest, AnyCrsIsPlacedInTheWorldFrame) {
  const Terrain plane = [](double x, double y) { return 0.1 * x - 0.05 * y + 3.0; };
  const io::ReferenceDem utm(WriteUtmReference(dir_ / "utm.tif", plane, 0.0), Georef());
  const io::ReferenceDem geo(WriteGeographicReference(dir_ / "geo.tif", plane), Georef(),
                             {true, 0.3});
  EXPECT_NEAR(utm.post_spacing_m(), 1.0, 0.01);
  EXPECT_NEAR(geo.post_spacing_m(), 0.76, 0.05);  // 1e-5° of longitude at 46.5° N
  for (const io::ReferenceDem* ref : {&utm, &geo}) {
    const io::ReferenceGrid grid = ref->Resample({0.0, -20.0}, {30.0, 20.0});
    ASSERT_GT(grid.ValidNodes(), 500u) << ref->file();
    for (const Eigen::Vector2d& p : {Eigen::Vector2d(5.3, -12.1), Eigen::Vector2d(24.0, 17.7)}) {
      EXPECT_NEAR(grid.HeightAt(p.x(), p.y()), plane(p.x(), p.y()), 0.02)
          << ref->file() << " at " << p.transpose();
    }
  }
  // σ: band 2 of the UTM file (1 mm here), reference.sigma_m for the one-band file.
  const io::ReferenceGrid g = geo.Resample({0.0, 0.0}, {5.0, 5.0});
  EXPECT_NEAR(g.sigma_m[g.sigma_m.size() / 2], 0.3, 1e-6);
  // The footprint covers what was written.
  EXPECT_TRUE(utm.footprint_world().contains(Eigen::Vector2d(90.0, 50.0)));
  EXPECT_FALSE(utm.footprint_world().contains(Eigen::Vector2d(120.0, 0.0)));
}

TEST_F(ReferenceDemTest, OneThatCannotBePlacedIsRefusedNamingTheFileAndWhy) {
  const Terrain flat = [](double, double) { return 0.0; };
  const fs::path good = WriteUtmReference(dir_ / "good.tif", flat, 0.1);
  auto refused = [&](const io::RasterFrame& frame, const std::vector<float>& z,
                     const std::string& name, const std::string& why) {
    const fs::path path = dir_ / name;
    io::WriteFloatGeoTiff(path, frame, {{&z, "elevation", "m"}});
    try {
      io::ReferenceDem ref(path, Georef());
      ADD_FAILURE() << name << " was accepted";
    } catch (const io::IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  io::RasterFrame frame;
  frame.width = frame.height = 10;
  frame.geotransform = {Georef().origin_projected().x(), 1, 0,
                        Georef().origin_projected().y(), 0, -1};
  const std::vector<float> z(100, 1.0f);
  io::RasterFrame no_crs = frame;
  refused(no_crs, z, "no_crs.tif", "has no CRS");
  io::RasterFrame local = frame;
  local.wkt = "LOCAL_CS[\"site grid\",UNIT[\"metre\",1]]";
  refused(local, z, "local.tif", "cannot be transformed to geographic coordinates");
  io::RasterFrame mars = frame;
  mars.wkt =
      "GEOGCS[\"Mars 2000\",DATUM[\"D_Mars_2000\",SPHEROID[\"Mars_2000_IAU_IAG\",3396190,0]],"
      "PRIMEM[\"Reference_Meridian\",0],UNIT[\"degree\",0.0174532925199433]]";
  mars.geotransform = {6.5, 1e-4, 0, 46.6, 0, -1e-4};
  refused(mars, z, "mars.tif", "is of another body");
  io::RasterFrame empty = frame;
  empty.wkt = Georef().wkt();
  refused(empty, std::vector<float>(100, NAN), "all_nan.tif", "holds no height");
  EXPECT_THROW(io::ReferenceDem(dir_ / "missing.tif", Georef()), io::IoError);
  EXPECT_NO_THROW(io::ReferenceDem(good, Georef()));
}

namespace {

// The rover's ground over a 40 m strip along x (|y| <= 8 m), as PatchAccumulator gives it: posts
// at 1 m in the chain's frame, a post at p holding the terrain at C·p (C the chain's
// misplacement), 1 cm of noise.
std::vector<mapper::Post> RoverPosts(const Terrain& terrain, const Eigen::Isometry3d& C) {
  std::vector<mapper::Post> posts;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double x = 0.0; x <= 40.0; x += 1.0) {
    for (double y = -8.0; y <= 8.0; y += 1.0) {
      const Eigen::Vector3d truth = C * Eigen::Vector3d(x, y, 0.0);
      posts.push_back({Eigen::Vector3d(x, y, terrain(truth.x(), truth.y()) + noise(rng)), 25});
    }
  }
  return posts;
}

std::vector<Eigen::Isometry3d> Poses() {
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k <= 20; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(2.0 * k, 0.0, 0.5);
    poses.push_back(T);
  }
  return poses;
}

Eigen::Isometry3d Misplacement(double dx, double dy, double yaw_deg) {
  return Eigen::Translation3d(dx, dy, 0.0) *
         Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
}

mapper::ReferenceMatch Match(const fs::path& dir, const Terrain& terrain,
                             const Eigen::Isometry3d& C, double sigma_m,
                             const mapper::ReferenceOptions& options = {}) {
  const io::ReferenceDem ref(WriteUtmReference(dir / "ref.tif", terrain, sigma_m), Georef());
  return mapper::MatchReference(RoverPosts(terrain, C), ref, 0, Poses(),
                                Eigen::Isometry3d::Identity(), options,
                                registration::RegistrationOptions{});
}

}  // namespace

// A chain 0.6 m and 1° off, a reference of 0.1 m noise: the match finds the misplacement within
// 3σ of what it states.
TEST_F(ReferenceDemTest, AMisplacedPatchIsFoundWithinItsSigma) {
  const Eigen::Isometry3d C = Misplacement(0.6, -0.4, 1.0);
  const mapper::ReferenceMatch m = Match(dir_, Bumpy(), C, 0.1);
  ASSERT_TRUE(m.matched) << m.reason;
  EXPECT_GT(m.posts, 400u);
  EXPECT_LT(m.rms_after_m, m.rms_before_m);
  // Where the patch's centre lands, and the heading.
  const Eigen::Vector3d centre(20.0, 0.0, 0.0);
  const Eigen::Vector2d error = (m.correction * centre - C * centre).head<2>();
  EXPECT_LT(std::abs(error.x()), 3.0 * m.sigma_x_m + 0.02) << error.transpose();
  EXPECT_LT(std::abs(error.y()), 3.0 * m.sigma_y_m + 0.02) << error.transpose();
  const double yaw = std::atan2(m.correction(1, 0), m.correction(0, 0)) * 180.0 / M_PI;
  EXPECT_LT(std::abs(yaw - 1.0), 3.0 * m.sigma_yaw_deg + 0.05) << yaw;
  EXPECT_LT(m.sigma_x_m, 0.3);
  EXPECT_LT(m.sigma_yaw_deg, 0.6);
  // The factor sits on a frame of the window, its pose moved as the patch was.
  EXPECT_LE(m.frame, 20u);
  const Eigen::Vector3d t = m.T_world_body.translation();
  const Eigen::Vector3d expected = C * Poses()[m.frame].translation();
  EXPECT_LT((t - expected).head<2>().norm(), 3.0 * std::hypot(m.sigma_x_m, m.sigma_y_m) + 0.05);
  EXPECT_FALSE(m.vertical_absolute);
  EXPECT_GT(m.information(2, 2), 0.0);
  // Roll is not held: what it has comes through the lever from the patch's centre to the frame
  // (a tilt of the frame moves the patch by its height above it).
  EXPECT_LT(m.information(0, 0), 0.01 * m.information(2, 2));
}

TEST_F(ReferenceDemTest, APlaneIsRefusedAsIllConditioned) {
  const Terrain plane = [](double x, double y) { return 0.03 * x + 0.01 * y; };
  const mapper::ReferenceMatch m = Match(dir_, plane, Misplacement(0.3, 0.2, 0.5), 0.2);
  EXPECT_FALSE(m.matched);
  EXPECT_NE(m.reason.find("ill-conditioned"), std::string::npos) << m.reason;
}

// Ripples across x: x is fixed (up to their wavelength), y along their crests is not.
TEST_F(ReferenceDemTest, RipplesOfOneDirectionAreRefusedNamingTheFreeDirection) {
  const Terrain ripples = [](double x, double) { return 0.4 * std::sin(2.0 * M_PI * x / 7.0); };
  const mapper::ReferenceMatch m = Match(dir_, ripples, Misplacement(0.3, 0.2, 0.0), 0.05);
  EXPECT_FALSE(m.matched);
  EXPECT_TRUE(m.reason.find("ill-conditioned: y") != std::string::npos ||
              m.reason.find("ambiguous") != std::string::npos)
      << m.reason;
}

// An egg-crate of 5 m: every 5 m the same relief, and the search reaches the next one.
TEST_F(ReferenceDemTest, APeriodicFieldIsRefusedAsAmbiguous) {
  const Terrain crate = [](double x, double y) {
    return 0.5 * std::sin(2.0 * M_PI * x / 5.0) * std::sin(2.0 * M_PI * y / 5.0);
  };
  mapper::ReferenceOptions o;
  o.search_m = 6.0;
  const mapper::ReferenceMatch m = Match(dir_, crate, Misplacement(0.3, 0.2, 0.0), 0.05, o);
  EXPECT_FALSE(m.matched);
  EXPECT_NE(m.reason.find("ambiguous"), std::string::npos) << m.reason;
}

TEST_F(ReferenceDemTest, BadOptionsAreRefusedNamingTheKey) {
  mapper::ReferenceOptions o;
  o.every_m = 0.0;
  EXPECT_THROW(mapper::Validate(o), std::invalid_argument);
  o = {};
  o.min_relief_ratio = 0.5;
  try {
    mapper::Validate(o);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("reference.min_relief_ratio"), std::string::npos);
  }
}

// A frame's points binned in its body frame and placed by its pose; a window merges frames at a
// post spacing and forgets the frames dropped.
TEST(Patches, FramesArePlacedByTheirPosesAndMergedAtThePostSpacing) {
  registration::PointCloud cloud;
  for (double x = 0.05; x < 4.0; x += 0.1)
    for (double y = -2.0 + 0.05; y < 2.0; y += 0.1) cloud.points.emplace_back(x, y, 0.2 * x);
  std::vector<unsigned char> keep(cloud.size(), 1);
  keep[0] = 0;
  cloud.points[0].z() = 100.0;  // flagged: must not count
  const mapper::FrameBins bins = mapper::BinFrame(cloud, keep);
  ASSERT_FALSE(bins.mean.empty());
  EXPECT_FALSE(bins.weighted);
  mapper::PatchAccumulator acc;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10.0, 5.0, 1.0);
  acc.Add(0, T, bins);
  T.translation().x() += 4.0;
  acc.Add(1, T, bins);
  const std::vector<mapper::Post> posts = acc.Window(0, 1, 1.0);
  ASSERT_GE(posts.size(), 30u);
  for (const mapper::Post& p : posts) {
    // The plane z = 0.2 x in each frame's body: world z = 1 + 0.2 (x_world − frame's x); the
    // post at the seam (x 13.5-14.5) holds both frames' points.
    if (std::abs(p.p.x() - 14.0) < 0.6) continue;
    const double body_x = p.p.x() < 14.0 ? p.p.x() - 10.0 : p.p.x() - 14.0;
    EXPECT_NEAR(p.p.z(), 1.0 + 0.2 * body_x, 0.11) << p.p.transpose();
    EXPECT_GE(p.p.x(), 10.0);
    EXPECT_LE(p.p.x(), 18.0);
  }
  acc.DropBefore(1);
  for (const mapper::Post& p : acc.Window(0, 1, 1.0)) EXPECT_GE(p.p.x(), 13.9);
  // West and south of the origin (negative bin indices) the same frame gives as many posts.
  mapper::PatchAccumulator west;
  T.translation() = Eigen::Vector3d(-50.0, -30.0, 1.0);
  west.Add(0, T, bins);
  mapper::PatchAccumulator east;
  T.translation() = Eigen::Vector3d(50.0, 30.0, 1.0);
  east.Add(0, T, bins);
  EXPECT_EQ(west.Window(0, 0, 1.0).size(), east.Window(0, 0, 1.0).size());
}

// Posts from points with variances: within a bin, a stray point (a stereo outlier the mask
// missed) is left out and precise points outweigh imprecise ones; a post whose σ exceeds the
// window's limit (far stereo ground) is left out, and its σ is that of the weighted mean.
TEST(Patches, AStrayPointAndImpreciseGroundDoNotMoveAPost) {
  registration::PointCloud cloud;
  auto add = [&](double x, double y, double z, double sigma) {
    cloud.points.emplace_back(x, y, z);
    cloud.covariances.push_back(Eigen::Vector3d(1e-4, 1e-4, sigma * sigma).asDiagonal());
  };
  // Post (0, 0) of 1 m: nine precise points at z 0 (σ 0.02 m), one imprecise at 0.3 (σ 0.3 m),
  // one stray at 5 m (σ 0.02 m: its own variance does not give it away).
  for (int i = 0; i < 9; ++i) add(0.05 + 0.02 * i, 0.05, 0.0, 0.02);
  add(0.1, 0.1, 0.3, 0.3);
  add(0.15, 0.15, 5.0, 0.02);
  // Post (10, 0): only imprecise points (σ 0.5 m), enough of them.
  for (int i = 0; i < 9; ++i) add(10.05 + 0.02 * i, 0.05, 1.0, 0.5);
  const mapper::FrameBins bins = mapper::BinFrame(cloud, {});
  ASSERT_TRUE(bins.weighted);
  mapper::PatchAccumulator acc;
  acc.Add(0, Eigen::Isometry3d::Identity(), bins);
  std::vector<mapper::Post> posts = acc.Window(0, 0, 1.0);
  ASSERT_EQ(posts.size(), 2u);
  std::sort(posts.begin(), posts.end(),
            [](const mapper::Post& a, const mapper::Post& b) { return a.p.x() < b.p.x(); });
  // The stray point out, the imprecise one weighing 1/225 of a precise one.
  const double kMean = 0.3 / 0.09 / (9.0 / 0.0004 + 1.0 / 0.09);
  EXPECT_EQ(posts[0].points, 10u);
  EXPECT_NEAR(posts[0].p.z(), kMean, 1e-9);
  EXPECT_NEAR(posts[0].sigma_m, 1.0 / std::sqrt(9.0 / 0.0004 + 1.0 / 0.09), 1e-9);
  EXPECT_NEAR(posts[1].sigma_m, 0.5 / 3.0, 1e-9);
  // A limit of 0.1 m leaves the imprecise post out.
  posts = acc.Window(0, 0, 1.0, 0.1);
  ASSERT_EQ(posts.size(), 1u);
  EXPECT_LT(posts[0].p.x(), 1.0);
  // Two frames over one post: the height is their weighted median, not pulled by the stray one.
  registration::PointCloud stray;
  for (int i = 0; i < 9; ++i) {
    stray.points.emplace_back(0.05 + 0.02 * i, 0.05, 2.0);
    stray.covariances.push_back(Eigen::Vector3d(1e-4, 1e-4, 0.03 * 0.03).asDiagonal());
  }
  acc.Add(1, Eigen::Isometry3d::Identity(), mapper::BinFrame(stray, {}));
  acc.Add(2, Eigen::Isometry3d::Identity(), bins);
  posts = acc.Window(0, 2, 1.0, 0.1);
  ASSERT_EQ(posts.size(), 1u);
  EXPECT_NEAR(posts[0].p.z(), kMean, 1e-9);
}

// LoopInformation: a pose factor's information at frame `to` (world axes, about its position)
// as a left perturbation δ of T_from_to in frame `from`: e = A δ for small δ, checked by finite
// differences against T_to' = T_from · Exp(δ) · T_from_to.
TEST(Revisit, LoopInformationIsThePoseInformationMovedToTheFromFrame) {
  Eigen::Isometry3d T_from = Eigen::Isometry3d::Identity();
  T_from.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()).matrix();
  T_from.translation() = Eigen::Vector3d(12.0, -3.0, 0.5);
  Eigen::Isometry3d T_ft = Eigen::Isometry3d::Identity();
  T_ft.linear() = Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitZ()).matrix();
  T_ft.translation() = Eigen::Vector3d(8.0, 5.0, -0.3);
  const Eigen::Isometry3d T_to = T_from * T_ft;
  graph::Matrix6d info = graph::Matrix6d::Zero();
  info.diagonal() << 0.0, 0.0, 1e4, 100.0, 200.0, 400.0;
  const graph::Matrix6d L = mapper::LoopInformation(info, T_from, T_ft);
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0.0, 1e-4);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::Matrix<double, 6, 1> d;
    for (int i = 0; i < 6; ++i) d(i) = n(rng);
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() = Eigen::AngleAxisd(d.head<3>().norm(), d.head<3>().normalized()).matrix();
    D.translation() = d.tail<3>();
    const Eigen::Isometry3d T2 = T_from * D * T_ft;
    Eigen::Matrix<double, 6, 1> e;
    const Eigen::AngleAxisd aa(T2.linear() * T_to.linear().transpose());
    e << aa.angle() * aa.axis(), T2.translation() - T_to.translation();
    EXPECT_NEAR(d.dot(L * d), e.dot(info * e), 1e-3 * e.dot(info * e) + 1e-12) << trial;
  }
}
