#pragma once
// `rovermap mosaic`: many dem.tif files (docs/design.md §6) fused into one north-up COG on a
// common grid. Each input is resampled onto the output grid with GDAL's warper, tile by tile,
// optionally after co-registration onto the mosaic of the inputs before it, and fused by inverse
// variance.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "mosaic/MosaicOptions.hpp"
#include "registration/Options.hpp"

namespace rovermap::mosaic {

/// Output band numbers (1-based, GDAL order).
constexpr int kElevationBand = 1;     ///< fused elevation [m]
constexpr int kStddevBand = 2;        ///< fused standard deviation [m]
constexpr int kCountBand = 3;         ///< summed point count
constexpr int kDisagreementBand = 4;  ///< inputs beyond disagreement_sigma of the fused value

/// What co-registration did to one input (all zero for the first input and when it is off).
struct InputReport {
  std::string file;
  bool reference = false;  ///< the first input: the others are registered onto it and on
  bool overlaps = false;   ///< enough overlap with the inputs before it to register
  bool applied = false;    ///< a correction was applied
  /// "reference", "registered", "refused", "no_overlap", "failed: ...", "off"
  std::string status;
  std::string reason;  ///< why no correction was applied ("" when one was, and for the first)
  /// The correction found, applied or not (`applied`), about `origin_m`
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();  ///< [m] east, north, up
  Eigen::Vector3d rotation_deg = Eigen::Vector3d::Zero();   ///< [deg] rotation vector
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  ///< [m] output CRS: the overlap's centre
  /// Smallest / largest eigenvalue of the last match's information (rotations in metres of arc)
  double conditioning = 0.0;
  std::string unconstrained;      ///< directions the overlap does not constrain: not corrected
  std::size_t overlap_cells = 0;  ///< output cells both it and the mosaic before it cover
  double inlier_ratio = 0.0;      ///< the matcher's inliers / sampled points
  int iterations = 0;
  std::size_t disagreement_before = 0;  ///< overlap cells beyond disagreement_sigma, uncorrected
  std::size_t disagreement_after = 0;   ///< the same after the correction
  double rms_before_m = 0.0;            ///< [m] RMS height difference over the overlap
  double rms_after_m = 0.0;             ///< [m] with the correction found
};

/// What was written.
struct MosaicResult {
  int width = 0;                         ///< [cells]
  int height = 0;                        ///< [cells]
  std::array<double, 6> geotransform{};  ///< GDAL order, north-up
  std::string wkt;                       ///< output CRS
  double cell_size_m = 0.0;              ///< [m]
  int tiles = 0;                         ///< tiles fused
  std::size_t valid_cells = 0;           ///< cells with a fused elevation
  std::vector<InputReport> inputs;       ///< one per input, in order
};

/// Fuses `inputs` into the COG `out`, written atomically (temporary files in its folder, then a
/// rename; none is left behind on failure). Per cell, with w_i = 1/σ_i²:
/// z = Σ w_i z_i / Σ w_i, σ = (Σ w_i)^-1/2, count = Σ count_i, disagreement = Σ d_i + the inputs
/// with |z_i − z| > disagreement_sigma · sqrt(σ_i² + σ²), where d_i is band 4 of an input that
/// is itself a mosaic (0 for a dem.tif). `registration` are the matcher's options (the residual
/// is forced to point-to-plane, use_uncertainty on). When `report` is not empty, the per-input
/// report is written there as JSON (atomically, after the mosaic).
/// @throw std::invalid_argument if `options` make no sense (message names the mosaic. key).
/// @throw io::IoError naming the file if an input is missing, not a GeoTIFF, lacks the three
///        bands, a geotransform or a CRS, or if the output cannot be written.
MosaicResult BuildMosaic(const std::vector<std::filesystem::path>& inputs,
                         const std::filesystem::path& out, const std::filesystem::path& report,
                         const MosaicOptions& options,
                         const registration::RegistrationOptions& registration);

/// Where the report of the mosaic `out` goes: beside it, named after it (`NAME.json` for
/// `NAME.tif`), so that mosaics of different names share a folder. Equals `out` when `out`
/// ends in `.json`.
std::filesystem::path MosaicReportPath(const std::filesystem::path& out);

/// The report as JSON text (NAME.json beside NAME.tif; MosaicReportPath).
std::string MosaicReportJson(const MosaicResult& result, const MosaicOptions& options);

// The same mosaic in three steps, for a campaign that runs them as separate jobs (apps/Campaign):
// PlanMosaic (sequential: co-registration), FuseMosaicPart for each of `parts` bands of tile rows
// (independent), AssembleMosaic (the parts into the COG). The COG is the one BuildMosaic writes.

/// Step 1's outcome: the inputs, what co-registration found and reported, and the grid.
struct MosaicPlan {
  std::vector<std::filesystem::path> files;
  MosaicResult result;  ///< grid and per-input reports; tiles and valid_cells are 0 here
  /// Per input, the rigid correction p' = origin + T·(p − origin) in the output CRS [m].
  std::vector<Eigen::Matrix4d> corrections;
  std::vector<Eigen::Vector3d> correction_origins;
};

/// Opens and places the inputs, makes the grid, co-registers (when options.coregister).
/// @throw as BuildMosaic.
MosaicPlan PlanMosaic(const std::vector<std::filesystem::path>& inputs,
                      const MosaicOptions& options,
                      const registration::RegistrationOptions& registration);

/// The plan as JSON text (doubles round-trip exactly), and back.
/// @throw io::IoError naming `file` if the text is not a plan.
std::string MosaicPlanJson(const MosaicPlan& plan);
MosaicPlan ParseMosaicPlan(const std::string& text, const std::filesystem::path& file);

/// The rows of cells [first, second) of part `part` of `parts`: whole rows of tiles, as evenly
/// as they go (empty when there are more parts than rows of tiles).
std::pair<int, int> MosaicPartRows(const MosaicPlan& plan, int part, int parts,
                                   const MosaicOptions& options);

/// Step 2: fuses the rows of part `part` into the GeoTIFF `out` (atomically; nothing is written
/// for an empty part). Reopens the inputs, which must be the ones planned.
/// @throw io::IoError naming the file if an input changed since the plan or `out` cannot be
///        written; std::invalid_argument if `part` is not in [0, parts).
void FuseMosaicPart(const MosaicPlan& plan, int part, int parts, const std::filesystem::path& out,
                    const MosaicOptions& options);

/// Step 3: the parts (every non-empty part of `parts`, written by FuseMosaicPart into
/// `part_file(p)`) into the COG `out` and the report, as BuildMosaic.
/// @throw io::IoError naming a missing or unreadable part, or `out` if it cannot be written.
MosaicResult AssembleMosaic(const MosaicPlan& plan, int parts,
                            const std::function<std::filesystem::path(int)>& part_file,
                            const std::filesystem::path& out, const std::filesystem::path& report,
                            const MosaicOptions& options);

}  // namespace rovermap::mosaic
