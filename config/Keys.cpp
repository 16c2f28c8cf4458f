#include "config/Keys.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

namespace rovermap::config::detail {
namespace {

using registration::Acceleration;
using registration::Convergence;
using registration::Criterion;
using registration::Geometry;
using registration::RegistrationOptions;
using registration::Residual;
using registration::Solver;

const EnumNames<Geometry> kGeometryNames = {{"surface", Geometry::kSurface},
                                            {"curve", Geometry::kCurve}};
const EnumNames<Criterion> kCriterionNames = {{"nonsymmetric", Criterion::kNonSymmetric},
                                              {"symmetric", Criterion::kSymmetric}};
const EnumNames<Solver> kSolverNames = {{"svd", Solver::kSvd},
                                        {"dual_quaternion", Solver::kDualQuaternion}};
const EnumNames<Residual> kResidualNames = {{"auto", Residual::kAuto},
                                            {"point_to_point", Residual::kPointToPoint},
                                            {"point_to_plane", Residual::kPointToPlane}};
const EnumNames<Convergence> kConvergenceNames = {{"absolute", Convergence::kAbsolute},
                                                  {"relative", Convergence::kRelative}};
const EnumNames<Acceleration> kAccelerationNames = {{"auto", Acceleration::kAuto},
                                                    {"none", Acceleration::kNone},
                                                    {"anderson", Acceleration::kAnderson}};
const EnumNames<stereo::Algorithm> kStereoAlgorithmNames = {
    {"sgbm_3way", stereo::Algorithm::kSgbm3Way},
    {"sgbm", stereo::Algorithm::kSgbm},
    {"sgbm_hh", stereo::Algorithm::kSgbmHh},
    {"bm", stereo::Algorithm::kBm}};
const EnumNames<sim::PathShape> kPathShapeNames = {{"straight", sim::PathShape::kStraight},
                                                   {"curves", sim::PathShape::kCurves},
                                                   {"loop", sim::PathShape::kLoop},
                                                   {"out_and_back", sim::PathShape::kOutAndBack}};
const EnumNames<mapper::Reference> kReferenceNames = {{"previous", mapper::Reference::kPrevious},
                                                      {"local_map", mapper::Reference::kLocalMap}};
const EnumNames<io::SensorType> kBagSensorNames = {{"stereo", io::SensorType::kStereo},
                                                   {"cloud", io::SensorType::kCloud}};
const EnumNames<bool> kOdometrySourceNames = {{"topic", false}, {"tf", true}};
const EnumNames<bool> kTBodySensorSourceNames = {{"config", false}, {"tf_static", true}};
const EnumNames<std::string> kBodyNames = {{"earth", "earth"}, {"moon", "moon"}, {"mars", "mars"}};
const EnumNames<sim::SensorKind> kSensorKindNames = {{"stereo", sim::SensorKind::kStereo},
                                                     {"cloud", sim::SensorKind::kCloud}};

// The table. Key names follow the struct fields, except where docs/design.md §5 fixes the contract
// name (reference_distance). One line per key; DumpYaml and default.yaml follow this order.
std::vector<KeyEntry> BuildRegistry() {
  std::vector<KeyEntry> keys;

  using R = RegistrationOptions;
  SectionKeys<R> reg(keys, "registration", &Config::registration);
  reg.Enum("geometry", &R::geometry, kGeometryNames, "what the points sample (Zhang 1994, 4.2)");
  reg.Enum("criterion", &R::criterion, kCriterionNames, "symmetric: also target -> source");
  reg.Enum("solver", &R::solver, kSolverNames, "closed-form motion (Zhang 1994, App. A/B)");
  reg.Enum("residual", &R::residual, kResidualNames,
           "auto: point_to_plane for surfaces, point_to_point for curves");
  reg.Double("reference_distance", &R::reference_distance_m, "m", AtLeast(0),
             "Zhang's D; 0 = from the point spacing");
  reg.Double("dmax_initial_factor", &R::dmax_initial_factor, "factor", GreaterThan(0),
             "initial Dmax = factor * D (the paper: 20)");
  reg.Int("histogram_bins", &R::histogram_bins, "count", AtLeast(2),
          "distance histogram bins (poor registration)");
  reg.Double("histogram_valley_ratio", &R::histogram_valley_ratio, "ratio", OpenClosed(0, 1),
             "valley used if <= ratio * peak (paper: 0.6)");
  reg.Int("max_iterations", &R::max_iterations, "count", GreaterThan(0), "iteration cap");
  reg.Enum("convergence", &R::convergence, kConvergenceNames, "relative: the paper's 1 % test");
  reg.Double("relative_tolerance", &R::relative_tolerance, "ratio", GreaterThan(0),
             "relative test: |step| / |value| of r and t");
  reg.Double("translation_tolerance_m", &R::translation_tolerance_m, "m", AtLeast(0),
             "absolute test: translation step; 0 = D / 100");
  reg.Double("rotation_tolerance_deg", &R::rotation_tolerance_deg, "deg", AtLeast(0),
             "absolute test: rotation step");
  reg.Enum("acceleration", &R::acceleration, kAccelerationNames,
           "anderson: extrapolate the pose; auto: for point_to_point only");
  reg.Int("anderson_depth", &R::anderson_depth, "count", AtLeast(1),
          "past steps Anderson combines");
  reg.Double("orientation_threshold_deg", &R::orientation_threshold_deg, "deg", ClosedOpen(0, 180),
             "Theta: max normal/tangent angle; 0 = off");
  reg.Double("orientation_spread_sigmas", &R::orientation_spread_sigmas, "sigma", AtLeast(0),
             "Theta widened by this many expected orientation errors; 0 = plain test");
  reg.Bool("staged_orientation_test", &R::staged_orientation_test,
           "PCA-normal sources: test on the coarse subset first, keep it if it rejects pairs");
  reg.Double("orientation_min_rejected", &R::orientation_min_rejected, "ratio",
             Bounds{0, false, 1, false},
             "staged test: kept for the fine stage if it rejected this much; 0 = always");
  reg.Int("clean_sample_step", &R::clean_sample_step, "count", AtLeast(1),
          "staged test dropped (clean pairs): the fine stage matches every k-th sampled point");
  reg.Int("normal_neighbors", &R::normal_neighbors, "count", AtLeast(3),
          "PCA normal neighbours if the cloud has none");
  reg.Double("sample_voxel_factor", &R::sample_voxel_factor, "x D", AtLeast(0),
             "match one source point per voxel of this edge; 0 = all points");
  reg.Int("max_sample_points", &R::max_sample_points, "count", AtLeast(0),
          "match at most this many sampled points (every k-th); 0 = no limit");
  reg.Bool("coarse_to_fine", &R::coarse_to_fine, "subsample the source for the first iterations");
  reg.Int("coarse_iterations", &R::coarse_iterations, "count", AtLeast(0),
          "iterations on the subsampled source");
  reg.Int("coarse_step", &R::coarse_step, "count", AtLeast(1), "source stride while coarse");
  reg.Bool("use_uncertainty", &R::use_uncertainty, "weight, gate pairs by covariances, not Dmax");
  reg.Double("mahalanobis_gate", &R::mahalanobis_gate, "chi^2", GreaterThan(0),
             "on the squared Mahalanobis distance (3 dof, 95 %)");
  reg.Double(
      "seed_rotation_sigma_deg", &R::seed_rotation_sigma_deg, "deg", AtLeast(0),
      "seed's 1-sigma in the gate, shrinks with the steps; 0 = replay: mapper.seed_gate_scale");
  reg.Double(
      "seed_translation_sigma_m", &R::seed_translation_sigma_m, "m", AtLeast(0),
      "seed's 1-sigma in the gate, shrinks with the steps; 0 = replay: mapper.seed_gate_scale");
  reg.Int("min_pairs", &R::min_pairs, "count", AtLeast(3), "fewer pairs after gating = failure");
  reg.Bool("reuse_closest_points", &R::reuse_closest_points,
           "no search while the closest point cannot have changed; same result, faster");

  using S = stereo::StereoOptions;
  SectionKeys<S> st(keys, "stereo", &Config::stereo);
  st.Enum("algorithm", &S::algorithm, kStereoAlgorithmNames, "OpenCV matcher (sgbm_3way: 5 paths)");
  st.Int("min_disparity", &S::min_disparity, "px", AnyValue(), "smallest disparity searched");
  st.Int("num_disparities", &S::num_disparities, "px", AtLeast(0),
         "search range; a multiple of 16; 0 = reach the nearest ground the camera sees");
  st.Int("block_size", &S::block_size, "px", AtLeast(1), "odd window side (bm: 5..255)");
  st.Int("p1", &S::p1, "cost", AtLeast(0), "SGBM penalty, |dd| = 1; 0 = 8 * block^2");
  st.Int("p2", &S::p2, "cost", AtLeast(0), "SGBM penalty, |dd| > 1; 0 = 32 * block^2");
  st.Int("disp12_max_diff", &S::disp12_max_diff, "px", AtLeast(-1),
         "left-right consistency tolerance; -1 = off");
  st.Int("pre_filter_cap", &S::pre_filter_cap, "count", Bounds{1, false, 63, false},
         "prefilter clip");
  st.Int("uniqueness_ratio", &S::uniqueness_ratio, "%", Bounds{0, false, 100, false},
         "best cost margin over the second; 0 = off");
  st.Int("speckle_window_size", &S::speckle_window_size, "px", AtLeast(0),
         "remove disparity blobs smaller than this; 0 = off");
  st.Int("speckle_range", &S::speckle_range, "px", AtLeast(0), "disparity step inside a blob");
  st.Int("texture_threshold", &S::texture_threshold, "count", AtLeast(0),
         "bm only: minimum window texture");
  st.Int("subpixel_window_px", &S::subpixel_window_px, "px", AtLeast(0),
         "sub-pixel refinement window (Lucas-Kanade); odd >= 3, 0 = off");
  st.Double("disparity_sigma_px", &S::disparity_sigma_px, "px", AtLeast(0),
            "error model: sigma_z = z^2 * sigma_d / (f * b)");
  st.Double("pixel_sigma_px", &S::pixel_sigma_px, "px", AtLeast(0),
            "error model: image position noise (lateral)");
  st.Double("min_range_m", &S::min_range_m, "m", AtLeast(0), "drop nearer points");
  st.Double("max_range_m", &S::max_range_m, "m", GreaterThan(0), "drop farther points");
  st.Bool("compute_normals", &S::compute_normals, "normals from the organised image");
  st.Int("normal_step_px", &S::normal_step_px, "px", AtLeast(1), "neighbour offset for normals");
  st.Double("normal_max_depth_jump", &S::normal_max_depth_jump, "ratio", GreaterThan(0),
            "depth edge: |dz| / z per pixel of step");
  st.Double("fill_spacing_m", &S::fill_spacing_m, "m", AtLeast(0),
            "DEM only: points between neighbouring pixels this far apart; 0 = off");
  st.Double("fill_max_step_px", &S::fill_max_step_px, "px", AtLeast(0),
            "DEM fill: larger disparity steps are edges, not joined");
  st.Double("voxel_size_m", &S::voxel_size_m, "m", AtLeast(0), "voxel downsampling; 0 = off");

  using M = sim::SimOptions;
  SectionKeys<M> sim(keys, "sim", &Config::sim);
  sim.Int("seed", &M::seed, "count", AnyValue(), "same seed, same sequence");
  // ~1 kB of path and poses per frame are held in memory.
  sim.Int("frames", &M::frames, "count", Bounds{1, false, kMaxSimFrames, false},
          "frames in the sequence");
  sim.Double("frame_rate_hz", &M::frame_rate_hz, "Hz", GreaterThan(0), "frame rate");
  sim.Double("speed_m_s", &M::speed_m_s, "m/s", AtLeast(0), "rover ground speed");
  sim.Double("origin_latitude_deg", &M::origin_latitude_deg, "deg", Bounds{-90, false, 90, false},
             "geodetic origin (sequence.yaml)");
  sim.Double("origin_longitude_deg", &M::origin_longitude_deg, "deg",
             Bounds{-180, false, 180, false}, "geodetic origin");
  sim.Double("origin_altitude_m", &M::origin_altitude_m, "m", AnyValue(), "geodetic origin");
  sim.Double("terrain_size_m", &M::terrain_size_m, "m", GreaterThan(0),
             "edge of the square terrain");
  sim.Double("terrain_cell_m", &M::terrain_cell_m, "m", GreaterThan(0), "heightfield spacing");
  sim.Double("relief_m", &M::relief_m, "m", AtLeast(0), "fractal relief amplitude");
  sim.Double("relief_wavelength_m", &M::relief_wavelength_m, "m", GreaterThan(0),
             "largest relief wavelength");
  sim.Int("octaves", &M::octaves, "count", Bounds{1, false, 16, false}, "fractal octaves");
  sim.Double("roughness", &M::roughness, "ratio", Bounds{0, false, 1, false},
             "amplitude ratio between octaves");
  sim.Double("slope_x_deg", &M::slope_x_deg, "deg", Bounds{-45, false, 45, false},
             "regional slope rising to the east");
  sim.Double("slope_y_deg", &M::slope_y_deg, "deg", Bounds{-45, false, 45, false},
             "regional slope rising to the north");
  sim.Int("craters", &M::craters, "count", AtLeast(0), "crater count");
  sim.Double("crater_max_radius_m", &M::crater_max_radius_m, "m", GreaterThan(0), "largest crater");
  sim.Int("rocks", &M::rocks, "count", AtLeast(0), "rock count");
  sim.Double("rock_max_radius_m", &M::rock_max_radius_m, "m", GreaterThan(0), "largest rock");
  sim.Double("keep_out_m", &M::keep_out_m, "m", AtLeast(0), "no rocks this close to the path");
  sim.Enum("path", &M::path, kPathShapeNames, "rover path shape");
  sim.Double("turn_radius_m", &M::turn_radius_m, "m", GreaterThan(0),
             "loop radius / tightest curve radius");
  sim.Double("start_x_m", &M::start_x_m, "m", AnyValue(),
             "start position east of the terrain's centre");
  sim.Double("start_y_m", &M::start_y_m, "m", AnyValue(),
             "start position north of the terrain's centre");
  sim.Double("start_yaw_deg", &M::start_yaw_deg, "deg", AnyValue(),
             "start heading, from east counter-clockwise");
  sim.Double("wheelbase_m", &M::wheelbase_m, "m", GreaterThan(0), "pitch from the terrain");
  sim.Double("track_m", &M::track_m, "m", GreaterThan(0), "roll from the terrain");
  sim.Enum("sensor", &M::sensor, kSensorKindNames, "stereo images or PLY clouds");
  sim.Double("mast_height_m", &M::mast_height_m, "m", AnyValue(), "camera above the body origin");
  sim.Double("mast_forward_m", &M::mast_forward_m, "m", AnyValue(),
             "camera ahead of the body origin");
  sim.Double("camera_tilt_deg", &M::camera_tilt_deg, "deg", Bounds{-89, false, 89, false},
             "optical axis below the horizontal");
  sim.Double("baseline_m", &M::baseline_m, "m", GreaterThan(0), "stereo baseline");
  sim.Double("focal_px", &M::focal_px, "px", GreaterThan(0), "focal length");
  sim.Int("image_width", &M::image_width, "px", Bounds{16, false, kMaxImageSide, false},
          "image width");
  sim.Int("image_height", &M::image_height, "px", Bounds{16, false, kMaxImageSide, false},
          "image height");
  sim.Double("sun_elevation_deg", &M::sun_elevation_deg, "deg", Bounds{0, false, 90, false},
             "sun above the horizon");
  sim.Double("sun_azimuth_deg", &M::sun_azimuth_deg, "deg", AnyValue(),
             "sun direction, from east counter-clockwise");
  sim.Double("image_noise", &M::image_noise, "grey", AtLeast(0), "sensor noise sigma");
  sim.Double("max_range_m", &M::max_range_m, "m", GreaterThan(0), "farther is sky");
  sim.Double("baseline_error", &M::baseline_error, "ratio", Bounds{0, false, 0.2, false},
             "sigma of the rig's true baseline against the stated one, drawn per traverse; 0 = "
             "exact");
  sim.Double("mount_error_deg", &M::mount_error_deg, "deg", Bounds{0, false, 5, false},
             "sigma of the camera's true mounting rotation about each axis against the stated "
             "one, drawn per traverse; 0 = exact");
  sim.Int("cloud_stride_px", &M::cloud_stride_px, "px", AtLeast(1), "cloud mode: pixel stride");
  sim.Double("disparity_sigma_px", &M::disparity_sigma_px, "px", AtLeast(0),
             "cloud mode: disparity noise");
  sim.Double("pixel_sigma_px", &M::pixel_sigma_px, "px", AtLeast(0), "cloud mode: image noise");
  sim.Double("outlier_fraction", &M::outlier_fraction, "ratio", Bounds{0, false, 1, false},
             "cloud mode: points at a random depth");
  sim.Double("disparity_locking", &M::disparity_locking, "ratio", Bounds{0, false, 1, false},
             "cloud mode: sub-pixel disparity pulled toward whole pixels; 1 = whole pixels");
  sim.Double("range_quantisation_m", &M::range_quantisation_m, "m", AtLeast(0),
             "cloud mode: range rounded to bins of this size along the ray; 0 = off");
  sim.Bool("cloud_normals", &M::cloud_normals,
           "cloud mode: PLY frames carry the terrain's true normals; false: none, estimated as for "
           "a real sensor");
  sim.Int("odometry_seed", &M::odometry_seed, "count", AnyValue(),
          "seeds the odometry errors alone; 0 = sim.seed");
  sim.Double("odom_scale_error", &M::odom_scale_error, "ratio", GreaterThan(-1),
             "wheel odometry scale error");
  sim.Double("odom_slip_mean", &M::odom_slip_mean, "ratio", GreaterThan(-1), "mean slip");
  sim.Double("odom_slip_sigma", &M::odom_slip_sigma, "ratio", AtLeast(0), "per-step slip sigma");
  sim.Double("heading_bias_deg_s", &M::heading_bias_deg_s, "deg/s", AnyValue(),
             "heading-rate bias");
  sim.Double("heading_random_walk_deg_rt_s", &M::heading_random_walk_deg_rt_s, "deg/sqrt(s)",
             AtLeast(0), "heading random walk");
  sim.Int("gnss_every_frames", &M::gnss_every_frames, "frames", AtLeast(0),
          "write gnss.csv: a fix of the body origin every this many frames; 0 = none");
  sim.Double("gnss_sigma_m", &M::gnss_sigma_m, "m", GreaterThan(0),
             "GNSS noise and reported sigma, east and north");
  sim.Double("gnss_sigma_up_m", &M::gnss_sigma_up_m, "m", GreaterThan(0),
             "GNSS noise and reported sigma, up");
  sim.Double("gnss_outlier_fraction", &M::gnss_outlier_fraction, "fraction",
             Bounds{0, false, 1, false}, "fixes thrown gnss_outlier_m off (multipath)");
  sim.Double("gnss_outlier_m", &M::gnss_outlier_m, "m", AtLeast(0),
             "horizontal jump of a multipath fix");
  sim.Double(
      "reference_post_m", &M::reference_post_m, "m", AtLeast(0),
      "write reference_dem.tif: the true terrain averaged over posts this far apart; 0 = none");
  sim.Double("reference_sigma_m", &M::reference_sigma_m, "m", GreaterThan(0),
             "reference DEM: height noise, and its sigma band");
  sim.DoubleList("reference_offset_m", &M::reference_offset_m, "m", AnyValue(),
                 "reference DEM: east, north (2 numbers) of its georeferencing error");

  using D = dem::ElevationMapOptions;
  SectionKeys<D> dem_keys(keys, "dem", &Config::dem);
  dem_keys.Double("cell_size_m", &D::cell_size_m, "m", GreaterThan(0), "DEM cell edge");
  dem_keys.Int("tile_cells", &D::tile_cells, "count", Bounds{1, false, 4096, false},
               "cells along a tile edge (tiles allocated on first touch)");
  dem_keys.Double("mahalanobis_gate", &D::mahalanobis_gate, "chi^2", GreaterThan(0),
                  "squared height Mahalanobis gate (1 dof; 9 = 3 sigma)");
  dem_keys.Double("default_point_stddev_m", &D::default_point_stddev_m, "m", GreaterThan(0),
                  "height sigma of points without a covariance");
  dem_keys.Double("min_point_variance_m2", &D::min_point_variance_m2, "m^2", AtLeast(0),
                  "floor on a point's height variance");
  dem_keys.Double("max_horizontal_sigma_cells", &D::max_horizontal_sigma_cells, "cells", AtLeast(0),
                  "drop points whose horizontal sigma exceeds this; 0 = off");
  dem_keys.Int("min_support", &D::min_support, "count", AtLeast(1),
               "points a cell needs before it is published (else NaN)");
  dem_keys.Int("min_frame_span", &D::min_frame_span, "frames", AtLeast(1),
               "published only when its points span this many frames; 1 = off");
  dem_keys.Int("min_agreeing_neighbors", &D::min_agreeing_neighbors, "count",
               Bounds{0, false, 8, false},
               "published only with this many agreeing supported neighbours; 0 = off");
  dem_keys.Double("neighbor_step_m", &D::neighbor_step_m, "m", AtLeast(0),
                  "largest height step to an agreeing neighbour (or 3 sigma)");
  dem_keys.Bool("frame_points_correlated", &D::frame_points_correlated,
                "a frame's points in one cell weigh as one measurement");
  dem_keys.Bool("slope_aware_variance", &D::slope_aware_variance,
                "height variance along the surface normal and the slope to the cell centre");
  dem_keys.Bool("attitude_error_shared", &D::attitude_error_shared,
                "the pose's roll and pitch error does not average out over a cell's frames");
  dem_keys.Int("clear_min_rays", &D::clear_min_rays, "count", AtLeast(0),
               "a frame with this many rays under a published cell saw through it; the cell is "
               "emptied once more frames saw through it than saw it; 0 = off");
  dem_keys.Double("clear_margin_m", &D::clear_margin_m, "m", AtLeast(0),
                  "seen through: the cell lies above the ray by this + 3 sigma");
  dem_keys.Int("clear_ray_spacing_cells", &D::clear_ray_spacing_cells, "cells", AtLeast(1),
               "visibility rays go to one point per square of this many cells");

  using O = dem::OctoMapOptions;
  SectionKeys<O> octo(keys, "octomap", &Config::octomap);
  octo.Bool("enabled", &O::enabled, "fuse frames into an OctoMap and write map.bt");
  octo.Double("resolution_m", &O::resolution_m, "m", GreaterThan(0), "leaf voxel edge");
  octo.Double("max_range_m", &O::max_range_m, "m", AtLeast(0), "ray length cap; 0 = unlimited");
  octo.Double("prob_hit", &O::prob_hit, "probability", Bounds{0.5, true, 1, true},
              "occupancy update of an endpoint");
  octo.Double("prob_miss", &O::prob_miss, "probability", Bounds{0, true, 0.5, true},
              "occupancy update of a traversed voxel");
  octo.Bool("write_ot", &O::write_ot, "also write map.ot (with probabilities)");

  using T = terrain::TerrainOptions;
  SectionKeys<T> ter(keys, "terrain", &Config::terrain);
  ter.Bool("enabled", &T::enabled, "write terrain.tif and terrain.png with the DEM");
  ter.Double("footprint_m", &T::footprint_m, "m", GreaterThan(0),
             "side of the square footprint the layers are computed over (the rover's size)");
  ter.Double("max_slope_deg", &T::max_slope_deg, "deg", Bounds{0, true, 90, true},
             "steepest plane the rover may stand on");
  ter.Double("max_step_m", &T::max_step_m, "m", GreaterThan(0),
             "largest height difference within the footprint");
  ter.Double("max_roughness_m", &T::max_roughness_m, "m", GreaterThan(0),
             "largest RMS residual of the footprint's plane");
  ter.Double("min_coverage", &T::min_coverage, "ratio", OpenClosed(0, 1),
             "footprint cells that must hold a height, else unknown");
  ter.Double("uncertainty_sigmas", &T::uncertainty_sigmas, "sigma", AtLeast(0),
             "a limit within this many sigma of its layer marks the cell uncertain");
  ter.Int("tile_cells", &T::tile_cells, "cells", Bounds{16, false, 4096, false},
          "computed tile by tile, tiles in parallel");

  using E = eval::EvalOptions;
  SectionKeys<E> ev(keys, "eval", &Config::eval);
  ev.Double("association_tolerance_s", &E::association_tolerance_s, "s", AtLeast(0),
            "max |t_estimate - t_groundtruth| of a pair");
  ev.Double("rpe_delta_m", &E::rpe_delta_m, "m", GreaterThan(0),
            "RPE: ground-truth travel per pair");
  ev.DoubleList("segment_lengths_m", &E::segment_lengths_m, "m", GreaterThan(0),
                "KITTI-style segments (devkit: 100..800 for cars)");

  using P = mapper::MapperOptions;
  SectionKeys<P> map(keys, "mapper", &Config::mapper);
  map.Enum("reference", &P::reference, kReferenceNames,
           "register onto the previous good frame or a local map of the last frames");
  map.Int("local_map_frames", &P::local_map_frames, "count", AtLeast(1),
          "local_map: registered frames kept");
  map.Double("local_map_voxel_m", &P::local_map_voxel_m, "m", AtLeast(0),
             "local_map: voxel thinning; 0 = the registration's D");
  map.Int("min_points", &P::min_points, "count", AtLeast(3),
          "fewer usable points = bad frame (not registered, not fused)");
  map.Double("outlier_radius_factor", &P::outlier_radius_factor, "x spacing", AtLeast(0),
             "isolated point: few neighbours within factor * range * angular spacing; 0 = off");
  map.Int("outlier_min_neighbors", &P::outlier_min_neighbors, "count", Bounds{0, false, 16, false},
          "neighbours an unisolated point has within that radius");
  map.Double("registration_cell_px", &P::registration_cell_px, "px", AtLeast(0),
             "stereo: register range-aware voxels this many pixels wide; 0 = every point");
  map.Bool("use_point_covariances", &P::use_point_covariances,
           "register with the points' covariances when both frames carry them");
  map.Double("seed_gate_scale", &P::seed_gate_scale, "ratio", AtLeast(0),
             "covariance gate first opens by this x odometry sigma per step; 0 = sensor's alone");
  map.Double("min_inlier_ratio", &P::min_inlier_ratio, "ratio", Bounds{0, false, 1, false},
             "reject a registration with fewer inliers / sampled points");
  map.Double("max_rms_m", &P::max_rms_m, "m", GreaterThan(0),
             "reject a registration with a larger RMS residual");
  map.Double("correction_gate_sigma", &P::correction_gate_sigma, "sigma", GreaterThan(0),
             "reject a correction beyond this many odometry sigmas");
  map.Double("odometry_sigma_translation_ratio", &P::odometry_sigma_translation_ratio, "ratio",
             AtLeast(0), "odometry translation sigma per metre of step");
  map.Double("odometry_sigma_translation_m", &P::odometry_sigma_translation_m, "m", AtLeast(0),
             "odometry translation sigma per step (floor)");
  map.Double("odometry_sigma_rotation_deg_per_m", &P::odometry_sigma_rotation_deg_per_m, "deg/m",
             AtLeast(0), "odometry rotation sigma per metre of step");
  map.Double("odometry_sigma_rotation_deg", &P::odometry_sigma_rotation_deg, "deg", AtLeast(0),
             "odometry rotation sigma per step (floor)");
  map.Double("odometry_noise_translation_ratio", &P::odometry_noise_translation_ratio, "ratio",
             AtLeast(0), "odometry's typical translation error per metre of step (covariance)");
  map.Double("odometry_noise_translation_m", &P::odometry_noise_translation_m, "m", AtLeast(0),
             "odometry's typical translation error per step (floor)");
  map.Double("odometry_noise_rotation_deg_per_m", &P::odometry_noise_rotation_deg_per_m, "deg/m",
             AtLeast(0), "odometry's typical rotation error per metre of step (covariance)");
  map.Double("odometry_noise_rotation_deg", &P::odometry_noise_rotation_deg, "deg", AtLeast(0),
             "odometry's typical rotation error per step (floor)");
  map.Double("odometry_attitude_sigma_deg", &P::odometry_attitude_sigma_deg, "deg", AtLeast(0),
             "dead reckoning's roll and pitch as absolute, this sigma; 0 = chain alone");
  map.Double("registration_attitude_sigma_deg", &P::registration_attitude_sigma_deg, "deg",
             AtLeast(0), "roll and pitch uncertainty a registered increment adds (floor)");
  map.Double("stereo_covariance_scale", &P::stereo_covariance_scale, "ratio", AtLeast(1),
             "stereo frames' registration covariance x this (neighbouring pixels share errors)");
  map.Bool("image_check", &P::image_check,
           "stereo: fuse the increment the left images' tracked corners give (step 5b)");
  map.Double("image_covariance_scale", &P::image_covariance_scale, "ratio", AtLeast(1),
             "stereo: the image estimate's covariance x this");
  map.Double("image_gate_scale", &P::image_gate_scale, "ratio", AtLeast(1),
             "stereo: image estimate used if within chi2 of the registration's covariance x this");
  map.Double("stereo_systematic_ratio", &P::stereo_systematic_ratio, "ratio", AtLeast(0),
             "stereo: translation error per metre of a registered step that repeats (calibration)");
  map.Double("stereo_systematic_deg_per_m", &P::stereo_systematic_deg_per_m, "deg/m", AtLeast(0),
             "stereo: rotation error per metre of a registered step that repeats (calibration)");
  map.Double("stereo_systematic_frames", &P::stereo_systematic_frames, "frames", GreaterThan(0),
             "stereo: steps over which the systematic part persists");
  map.Double("rig_rotation_sigma_deg", &P::rig_rotation_sigma_deg, "deg",
             Bounds{0, false, 10, false},
             "rig mounting error per axis, in the DEM's sigma, unless sequence.yaml states it");
  map.Double("rig_scale_sigma", &P::rig_scale_sigma, "ratio", Bounds{0, false, 0.2, false},
             "rig depth scale error, in the DEM's sigma, unless sequence.yaml states it");
  map.Double("min_information", &P::min_information, "ratio", Bounds{0, false, 1, true},
             "directions with less information (relative to the best) keep dead reckoning");
  map.Double("min_information_over_noise", &P::min_information_over_noise, "ratio", AtLeast(0),
             "directions with less than this x what the normals' noise alone gives keep dead "
             "reckoning; 0 = off");
  map.Double("odometry_bias_rate", &P::odometry_bias_rate, "1/frame", Bounds{0, false, 1, false},
             "evidence each frame forgets in dead reckoning's bias estimate; 0 = off");
  map.Double("odometry_bias_prior_ratio", &P::odometry_bias_prior_ratio, "ratio", GreaterThan(0),
             "prior sigma of dead reckoning's bias per step, fraction of its sigma per step");
  map.Double("bias_min_information", &P::bias_min_information, "ratio", Bounds{0, false, 1, true},
             "directions with at least this information inform the bias estimate");

  using G = mapper::GraphOptions;
  SectionKeys<G> gr(keys, "graph", &Config::graph);
  gr.Bool("enabled", &G::enabled,
          "solve the pose graph when the recording has GNSS fixes (gnss.csv) or a reference DEM "
          "is given; false: frame to frame only");
  gr.Double("gnss_max_time_offset_s", &G::gnss_max_time_offset_s, "s", AtLeast(0),
            "a fix belongs to the nearest frame within this");
  gr.DoubleList("gnss_antenna_m", &G::gnss_antenna_m, "m", AnyValue(),
                "x y z (3 numbers) of the GNSS antenna in the body frame");
  gr.Double("fix_gate_chi2", &G::fix_gate_chi2, "chi2", GreaterThan(0),
            "a fix farther from the solution is rejected (3 dof; 16.27 = 99.9 %)");
  gr.Double("fix_huber_sigmas", &G::fix_huber_sigmas, "sigma", GreaterThan(0),
            "a fix's residual beyond this weighs linearly (Huber)");
  gr.Int("min_gnss_fixes", &G::min_gnss_fixes, "count", AtLeast(1),
         "fewer fixes left after the gate: the frame-to-frame trajectory is kept");
  gr.Int("covariance_max_frames", &G::covariance_max_frames, "frames", AtLeast(0),
         "the graph's marginal covariances up to this many frames (cost grows with the square); 0 "
         "= never");
  gr.Int("max_gate_rounds", &G::max_gate_rounds, "count", AtLeast(1),
         "solve-and-reject rounds at most");

  using RF = mapper::ReferenceOptions;
  SectionKeys<RF> rf(keys, "reference", &Config::reference);
  rf.Double("every_m", &RF::every_m, "m", GreaterThan(0),
            "replay --reference-dem: path between two matches of the rover's DEM");
  rf.Double("window_m", &RF::window_m, "m", GreaterThan(0), "the recent path whose DEM is matched");
  rf.Bool("sigma_band", &RF::sigma_band, "band 2 of the reference DEM holds its heights' sigma");
  rf.Double("sigma_m", &RF::sigma_m, "m", GreaterThan(0),
            "sigma of the reference's heights where no band gives it");
  rf.Bool("vertical_trusted", &RF::vertical_trusted,
          "the reference's vertical datum is the sequence's: a match also fixes the height");
  rf.Double("horizontal_sigma_m", &RF::horizontal_sigma_m, "m", GreaterThan(0),
            "sigma per axis of the reference's horizontal placement (its georeferencing)");
  rf.Bool("required", &RF::required,
          "an unusable reference DEM stops the run (exit 1) instead of being left out");
  rf.Double("search_m", &RF::search_m, "m", AtLeast(0),
            "horizontal search about the last match's correction");
  rf.Double("search_yaw_deg", &RF::search_yaw_deg, "deg", AtLeast(0), "heading search about it");
  rf.Double("min_relief_ratio", &RF::min_relief_ratio, "ratio", AtLeast(1),
            "x, y and heading need this x the information of the heights' noise alone");
  rf.Double("ambiguity_ratio", &RF::ambiguity_ratio, "ratio", AtLeast(1),
            "another placement fitting within this x the best one's RMS: refused as ambiguous");
  rf.Double("max_sigma_m", &RF::max_sigma_m, "m", GreaterThan(0),
            "a match with a larger sigma of x or y is refused");
  rf.Double("max_sigma_deg", &RF::max_sigma_deg, "deg", GreaterThan(0),
            "a match with a larger sigma of heading is refused");
  rf.Double("covariance_scale", &RF::covariance_scale, "ratio", AtLeast(1),
            "the match's covariance x this (neighbouring posts share errors)");
  rf.Int("min_posts", &RF::min_posts, "count", AtLeast(10),
         "fewer of the rover's posts over the reference: no match");
  rf.Double("max_post_sigma_m", &RF::max_post_sigma_m, "m", GreaterThan(0),
            "the rover's posts with a larger sigma (far stereo ground) are left out");

  using RV = mapper::RevisitOptions;
  SectionKeys<RV> rv(keys, "revisit", &Config::revisit);
  rv.Bool("enabled", &RV::enabled,
          "replay: match the recent ground onto the rover's own earlier ground (loop factors)");
  rv.Double("every_m", &RV::every_m, "m", GreaterThan(0),
            "path between two looks (each saves the recent ground for later ones)");
  rv.Double("window_m", &RV::window_m, "m", GreaterThan(0),
            "the recent path whose ground is matched");
  rv.Double("post_m", &RV::post_m, "m", GreaterThan(0), "post spacing of the ground matched");
  rv.Double("min_gap_m", &RV::min_gap_m, "m", GreaterThan(0),
            "path between the two passes, at least");
  rv.Double("search_m", &RV::search_m, "m", AtLeast(0),
            "horizontal search about the chain's placement");
  rv.Double("search_yaw_deg", &RV::search_yaw_deg, "deg", AtLeast(0), "heading search about it");
  rv.Double("min_overlap", &RV::min_overlap, "fraction", Bounds{0, true, 1, false},
            "of the recent posts over the earlier ground, at least");
  rv.Double("max_post_sigma_m", &RV::max_post_sigma_m, "m", GreaterThan(0),
            "posts with a larger sigma (far stereo ground) are left out");

  using V = mapper::ServeOptions;
  SectionKeys<V> serve(keys, "serve", &Config::serve);
  serve.Bool("use_inotify", &V::use_inotify, "watch the inbox with inotify (else poll)");
  serve.Double("poll_interval_s", &V::poll_interval_s, "s", GreaterThan(0),
               "between looks at the inbox when polling; longest wait otherwise");
  serve.Double("gap_timeout_s", &V::gap_timeout_s, "s", AtLeast(0),
               "a missing frame holds the queue this long, then is declared missing");
  serve.Int("max_gap_frames", &V::max_gap_frames, "frames", AtLeast(1),
            "a ready frame further than this beyond the next expected is rejected");
  serve.Int("publish_every", &V::publish_every, "frames", AtLeast(1),
            "publish the outputs after this many frames (and when idle, and on exit)");
  serve.Double("publish_share", &V::publish_share, "fraction", Bounds{0, false, 1, false},
               "largest share of the processing time publications may take while frames queue");
  serve.Int("publish_max_every", &V::publish_max_every, "frames", AtLeast(1),
            "a publication is never put off longer than this many frames");
  serve.Int("graph_window_frames", &V::graph_window_frames, "frames", AtLeast(0),
            "the pose graph solved over this many last frames at each publication; 0 = all");
  serve.Int("checkpoint_every", &V::checkpoint_every, "frames", AtLeast(1),
            "snapshot the state after this many frames (each is journalled)");
  serve.Double("checkpoint_share", &V::checkpoint_share, "fraction", Bounds{0, false, 1, false},
               "largest share of the processing time snapshots may take (0: no limit)");
  serve.Int("checkpoint_max_every", &V::checkpoint_max_every, "frames", AtLeast(1),
            "a snapshot is never put off longer than this many frames");
  serve.Double("status_interval_s", &V::status_interval_s, "s", AtLeast(0),
               "rewrite status.json at most this often while frames are queued");

  using B = BagConfig;
  SectionKeys<B> bag(keys, "bag", &Config::bag);
  bag.Enum<io::SensorType>("sensor", &B::sensor_type, kBagSensorNames,
                           "frames: left/right image pairs or PointCloud2 messages");
  bag.Name("left_image_topic", &B::left_image_topic, false,
           "sensor_msgs/Image or CompressedImage, rectified");
  bag.Name("right_image_topic", &B::right_image_topic, false, "the right images");
  bag.Name("left_info_topic", &B::left_info_topic, false,
           "sensor_msgs/CameraInfo: rectified projection P (clouds: optional)");
  bag.Name("right_info_topic", &B::right_info_topic, false, "P[0,3] = -fx * baseline");
  bag.Name("cloud_topic", &B::cloud_topic, false, "sensor_msgs/PointCloud2 (sensor: cloud)");
  bag.Double("pair_tolerance_s", &B::pair_tolerance_s, "s", AtLeast(0),
             "left and right stamps this close are a pair");
  bag.Enum<bool>("odometry_source", &B::odometry_from_tf, kOdometrySourceNames,
                 "nav_msgs/Odometry on odometry_topic, or /tf parent -> child");
  bag.Name("odometry_topic", &B::odometry_topic, false, "nav_msgs/Odometry");
  bag.Name("odometry_parent_frame", &B::odometry_parent_frame, false,
           "odometry_source: tf: the world-fixed frame");
  bag.Name("odometry_child_frame", &B::odometry_child_frame, false,
           "odometry_source: tf: the body frame");
  bag.Name("groundtruth_topic", &B::groundtruth_topic, true,
           "nav_msgs/Odometry or geometry_msgs/PoseStamped; \"\" = none");
  bag.Name("navsat_topic", &B::navsat_topic, false,
           "sensor_msgs/NavSatFix: its first fix is the origin unless origin_* are set; every fix "
           "a GNSS fix of the pose graph");
  bag.Double("navsat_sigma_m", &B::navsat_sigma_m, "m", GreaterThan(0),
             "sigma east, north and up of a NavSatFix whose covariance is unknown");
  bag.Enum<bool>("T_body_sensor_source", &B::T_body_sensor_from_tf_static, kTBodySensorSourceNames,
                 "the keys below, or /tf_static body_frame -> sensor_frame");
  bag.Name("body_frame", &B::body_frame, false, "T_body_sensor_source: tf_static");
  bag.Name("sensor_frame", &B::sensor_frame, false,
           "T_body_sensor_source: tf_static: the left camera (or cloud) frame");
  bag.DoubleList("T_body_sensor_translation", &B::T_body_sensor_translation, "m", AnyValue(),
                 "x y z (3 numbers) of the sensor in the body frame");
  bag.DoubleList(
      "T_body_sensor_rpy_deg", &B::T_body_sensor_rpy_deg, "deg", AnyValue(),
      "roll pitch yaw, R = Rz(y)Ry(p)Rx(r); [-90, 0, -90]: a level, forward-looking camera");
  // Setting any origin key makes the keys the origin (over the bag's NavSatFix).
  auto origin_key = [&](const std::string& key, double B::*field, const std::string& unit,
                        Bounds bounds, const std::string& doc) {
    bag.Double(key, field, unit, bounds, doc);
    keys.back().parse = [parse = keys.back().parse](const YAML::Node& n, Config& c) {
      parse(n, c);
      c.bag.origin_given = true;
    };
  };
  origin_key("origin_latitude_deg", &B::origin_latitude_deg, "deg", Bounds{-90, false, 90, false},
             "geodetic origin when set; else the first NavSatFix, else this");
  origin_key("origin_longitude_deg", &B::origin_longitude_deg, "deg",
             Bounds{-180, false, 180, false}, "geodetic origin");
  origin_key("origin_altitude_m", &B::origin_altitude_m, "m", AnyValue(), "geodetic origin");
  bag.Enum<std::string>("body", &B::body, kBodyNames, "the body the rover drove on");

  using MO = mosaic::MosaicOptions;
  SectionKeys<MO> mos(keys, "mosaic", &Config::mosaic);
  mos.Text("crs", &MO::crs,
           "output CRS (EPSG:32633, WKT, PROJ), projected in metres; \"\" = the first input's");
  mos.Double("cell_size_m", &MO::cell_size_m, "m", AtLeast(0),
             "output cell edge; 0 = the finest input's");
  mos.Double("disagreement_sigma", &MO::disagreement_sigma, "sigma", GreaterThan(0),
             "band 4 counts inputs beyond this many combined sigmas of the fused height");
  mos.Int("tile_cells", &MO::tile_cells, "cells", AtLeast(16),
          "edge of the square tiles fused one at a time (memory)");
  mos.Bool("coregister", &MO::coregister,
           "register each input onto the mosaic of those before it (point-to-plane)");
  mos.Int("min_overlap_cells", &MO::min_overlap_cells, "cells", AtLeast(3),
          "less overlap: the input is placed as it is and flagged");
  mos.Double(
      "min_information", &MO::min_information, "ratio", ClosedOpen(0, 1),
      "directions with less information (of the best) are not corrected; x, y, yaw: refused");
  mos.Double("min_improvement", &MO::min_improvement, "ratio", OpenClosed(0, 1),
             "applied only if the overlap's RMS height difference falls below this x its value");
  mos.Double("max_correction_m", &MO::max_correction_m, "m", AtLeast(0),
             "applied only if it shifts the overlap's centre by at most this (start error)");
  mos.Double("max_correction_deg", &MO::max_correction_deg, "deg", AtLeast(0),
             "applied only if it turns by at most this (start heading error)");
  mos.Double(
      "tilt_sigma_deg", &MO::tilt_sigma_deg, "deg", AtLeast(0),
      "sigma of the inputs' roll and pitch (gravity): a tilt is weighed against it; 0 = none");

  using CO = campaign::CampaignOptions;
  SectionKeys<CO> cam(keys, "campaign", &Config::campaign);
  cam.Int("cpus_per_task", &CO::cpus_per_task, "cores", AtLeast(1),
          "per replay task (sbatch --cpus-per-task; also sets how many run at once with --local)");
  cam.Int("memory_mb", &CO::memory_mb, "MB", AtLeast(64), "per replay task (sbatch --mem)");
  cam.Int("time_limit_min", &CO::time_limit_min, "min", AtLeast(0),
          "per task (sbatch --time); 0 = the partition's limit");
  cam.Text("partition", &CO::partition, "sbatch --partition; \"\" = the cluster's default");
  cam.Text("account", &CO::account, "sbatch --account; \"\" = the user's default");
  cam.Int("mosaic_tasks", &CO::mosaic_tasks, "tasks", AtLeast(1),
          "array tasks fusing the mosaic, each a band of rows of tiles");
  cam.Int("mosaic_memory_mb", &CO::mosaic_memory_mb, "MB", AtLeast(64),
          "per mosaic task (co-registration, a band of tiles, the assembly)");

  return keys;
}

// Shortest round-trip text; no forced ".0", for messages.
std::string FormatNumber(double value) {
  char buffer[64];
  // Whole numbers in full ("100000", not the shorter "1e+05"): bounds and counts read better.
  const bool whole = value == std::floor(value) && std::abs(value) < 1e15;
  const auto result =
      whole ? std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed)
            : std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

void CheckBounds(double value, const Bounds& bounds, const std::string& text) {
  const bool above_lo = bounds.lo_open ? value > bounds.lo : value >= bounds.lo;
  const bool below_hi = bounds.hi_open ? value < bounds.hi : value <= bounds.hi;
  if (!above_lo || !below_hi)
    throw ValueError("must be " + Describe(bounds) + " (got " + text + ")");
}

// YAML allows a leading '+', std::from_chars does not.
const char* SkipPlus(const std::string& text) {
  const char* first = text.data();
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') ++first;
  return first;
}

}  // namespace

const std::vector<KeyEntry>& Registry() {
  static const std::vector<KeyEntry> keys = BuildRegistry();
  return keys;
}

std::string Describe(const Bounds& bounds) {
  const bool has_lo = std::isfinite(bounds.lo);
  const bool has_hi = std::isfinite(bounds.hi);
  if (has_lo && has_hi) {
    return "in " + std::string(bounds.lo_open ? "(" : "[") + FormatNumber(bounds.lo) + ", " +
           FormatNumber(bounds.hi) + (bounds.hi_open ? ")" : "]");
  }
  if (has_lo) return std::string(bounds.lo_open ? "> " : ">= ") + FormatNumber(bounds.lo);
  if (has_hi) return std::string(bounds.hi_open ? "< " : "<= ") + FormatNumber(bounds.hi);
  return "";
}

std::string ScalarText(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return node.Scalar();
    case YAML::NodeType::Sequence:
      throw ValueError("expected a single value (got a list)");
    case YAML::NodeType::Map:
      throw ValueError("expected a single value (got a mapping)");
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      break;
  }
  throw ValueError("missing value");
}

int ParseInt(const YAML::Node& node, const Bounds& bounds) {
  const std::string text = ScalarText(node);
  const char* last = text.data() + text.size();
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(SkipPlus(text), last, value);
  const bool past_long_long = ec == std::errc::result_out_of_range && ptr == last;
  if (past_long_long ||
      (ec == std::errc() && ptr == last &&
       (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()))) {
    throw ValueError("too large for an integer (got " + text + ")");
  }
  if (ec != std::errc() || ptr != last) throw ValueError("expected an integer (got " + text + ")");
  CheckBounds(static_cast<double>(value), bounds, text);
  return static_cast<int>(value);
}

double ParseDouble(const YAML::Node& node, const Bounds& bounds) {
  const std::string text = ScalarText(node);
  const char* last = text.data() + text.size();
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(SkipPlus(text), last, value);
  if (ec == std::errc::result_out_of_range && ptr == last) {
    throw ValueError("out of range for a number (got " + text + ")");
  }
  if (ec != std::errc() || ptr != last) throw ValueError("expected a number (got " + text + ")");
  if (!std::isfinite(value)) throw ValueError("must be finite (got " + text + ")");
  CheckBounds(value, bounds, text);
  return value;
}

bool ParseBool(const YAML::Node& node) {
  const std::string text = ScalarText(node);
  bool value = false;
  if (!YAML::convert<bool>::decode(node, value)) {
    throw ValueError("expected true or false (got " + text + ")");
  }
  return value;
}

std::string ParseName(const YAML::Node& node, bool allow_empty) {
  const std::string text = node.IsNull() ? std::string() : ScalarText(node);
  if (text.empty()) {
    if (allow_empty) return text;
    throw ValueError("must not be empty");
  }
  for (const char c : text) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '/' ||
                    c == '.' || c == '-';
    if (!ok)
      throw ValueError("not a topic or frame name (letters, digits, _ / . -; got " + text + ")");
  }
  return text;
}

std::string QuoteText(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '\n') {
      quoted += "\\n";
      continue;
    }
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

std::string FormatDouble(double value) {
  std::string text = FormatNumber(value);
  // Keep 20.0 visibly a real number in the YAML.
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

}  // namespace rovermap::config::detail
