#pragma once
// PNG figures of `rovermap eval --plot DIR` (OpenCV drawing; written atomically).

#include <filesystem>
#include <string>
#include <vector>

#include "eval/DemComparison.hpp"
#include "eval/TrajectoryMetrics.hpp"

namespace rovermap::eval {

/// One estimate to draw: its legend label and its metrics (status kOk; others are skipped).
struct PlotEntry {
  std::string label;
  const TrajectoryMetrics* metrics = nullptr;
};

/// Top view of the ground truth (black) and each estimate aligned at the first pose (colours),
/// on the plane of the two coordinate axes along which the ground truth extends most.
/// @throw io::IoError naming the file if it cannot be written; std::invalid_argument if no entry
///        has status kOk.
void WriteTrajectoryPlot(const std::filesystem::path& path, const std::vector<PlotEntry>& entries);

/// Position error against ground-truth distance travelled: aligned at the first pose (solid) and
/// after the Umeyama alignment (thin), one colour per estimate.
/// @throw as WriteTrajectoryPlot.
void WriteErrorPlot(const std::filesystem::path& path, const std::vector<PlotEntry>& entries);

/// The DEM − reference error per comparison cell (blue below, red above, grey not compared),
/// scaled to ±max(p95_abs_m, 1 mm), with a colour bar; cropped to the compared cells and a
/// margin of 5 % (at least 2 cells).
/// @throw io::IoError naming the file if it cannot be written; std::invalid_argument if the
///        comparison has no cells.
void WriteDemErrorPlot(const std::filesystem::path& path, const DemComparison& comparison);

}  // namespace rovermap::eval
