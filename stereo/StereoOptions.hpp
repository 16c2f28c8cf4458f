#pragma once
// Options of the correlation stereo (OpenCV StereoSGBM / StereoBM) and of its error model.
// Every field is a config key under `stereo.` (config/default.yaml). Plain struct, no OpenCV.

namespace rovermap::stereo {

/// The matcher. kSgbm3Way is OpenCV's StereoSGBM MODE_SGBM_3WAY (5 directions, fast, the
/// default); kSgbm is MODE_SGBM; kSgbmHh is MODE_HH (8 directions, slow); kBm is StereoBM
/// (block matching, fastest, sparser).
enum class Algorithm { kSgbm3Way, kSgbm, kSgbmHh, kBm };

struct StereoOptions {
  Algorithm algorithm = Algorithm::kSgbm3Way;
  /// Smallest disparity searched [px].
  int min_disparity = 0;
  /// Disparity search range [px]; a positive multiple of 16, or 0 = from the camera's geometry
  /// (stereo::ResolveDisparities: enough to reach the nearest ground the camera sees). Too small a
  /// range does not drop near points: SGBM matches them at a wrong, smaller disparity, i.e. too
  /// far, below the ground, consistently from frame to frame.
  int num_disparities = 0;
  /// Matching window side [px]; odd (SGBM 1..11, BM 5..255).
  int block_size = 5;
  /// SGBM smoothness penalties for ±1 and larger disparity changes; 0 = 8·block² and 32·block²
  /// (OpenCV's recommendation for grey images).
  int p1 = 0;
  int p2 = 0;
  /// Left-right consistency: largest allowed difference [px] between the left disparity and
  /// the one found back from the right image; -1 = off.
  int disp12_max_diff = 1;
  /// Clip of the x-derivative prefilter (SGBM) / of the normalised intensity (BM).
  int pre_filter_cap = 31;
  /// Uniqueness: the best cost must beat the second best by this margin [%]; 0 = off.
  int uniqueness_ratio = 10;
  /// Speckle filter: connected disparity regions smaller than this are removed [px]; 0 = off.
  int speckle_window_size = 100;
  /// Speckle filter: largest disparity step inside one region [px].
  int speckle_range = 2;
  /// BM only: minimum texture (sum of |x-derivative| in the window) to accept a match.
  int texture_threshold = 10;
  /// Sub-pixel refinement of the matcher's disparity: one Lucas–Kanade step of the 1-D shift
  /// between the left image and the right one warped by the disparity, over a window of this
  /// odd side [px]; 0 = off (OpenCV's parabola interpolation alone, which pixel-locks and on
  /// the simulator's pairs read 0.06–0.18 px short, varying with the disparity).
  int subpixel_window_px = 9;

  /// Stereo error model: disparity noise σ_d [px]; depth σ_z = z²·σ_d / (f·b).
  double disparity_sigma_px = 0.2;
  /// Stereo error model: image position noise [px] (lateral covariance terms).
  double pixel_sigma_px = 0.3;

  /// Points nearer / farther than this from the camera are dropped [m].
  double min_range_m = 0.3;
  double max_range_m = 30.0;

  /// Surface normals from the organised disparity image (central differences between pixels
  /// `normal_step_px` apart); points without a usable neighbourhood are dropped and counted.
  bool compute_normals = true;
  int normal_step_px = 2;
  /// Neighbours whose depth differs by more than this fraction of the point's depth (per
  /// pixel of step) are across a depth edge and not used for the normal.
  double normal_max_depth_jump = 0.02;

  /// DEM fill [m]: between two neighbouring pixels (4-neighbours) farther apart than this,
  /// points every fill_spacing_m for the DEM only (StereoPointsResult::fill; registration and
  /// the OctoMap do not see them). Far ground is sampled more coarsely than the DEM's cells
  /// along the view, and pixel locking bunches the rows' depths, so without them one frame
  /// covers the cells in stripes of constant range (docs/stereo.md, "DEM fill between pixels"). 0 =
  /// off; keep it below dem.cell_size_m.
  double fill_spacing_m = 0.025;
  /// DEM fill: neighbours whose disparities differ by more than this [px] are across an edge
  /// and not joined. At least a whole pixel, the step of a pixel-locked disparity.
  double fill_max_step_px = 1.5;
  /// DEM fill: no fill point whose horizontal σ (the larger of the body-frame horizontal
  /// block's) exceeds this [m]; 0 = no limit. Not a config key: the pipeline sets it from
  /// the DEM (dem.max_horizontal_sigma_cells × dem.cell_size_m, with a margin), which would
  /// drop such points anyway. Far rows are the farthest apart, so without it most of a KITTI
  /// frame's fill points were made only to be dropped (docs/benchmarks.md, "Figures behind the
  /// frame pipeline's code").
  double fill_max_horizontal_sigma_m = 0.0;

  /// Voxel downsampling edge [m]; 0 = off. One fused point per occupied voxel.
  double voxel_size_m = 0.0;
};

}  // namespace rovermap::stereo
