#include "mosaic/Mosaic.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <fcntl.h>
#include <gdal_priv.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/TiledGeoTiff.hpp"
#include "mosaic/Coregister.hpp"
#include "mosaic/Fusion.hpp"
#include "mosaic/Warp.hpp"

namespace rovermap::mosaic {
namespace {

namespace fs = std::filesystem;
using detail::CellFusion;
using detail::DatasetPtr;
using detail::FusedLayers;
using detail::Input;
using detail::OutputGrid;
using detail::Window;

void CheckOptions(const MosaicOptions& options) {
  auto fail = [](const std::string& key, const std::string& why) {
    throw std::invalid_argument("mosaic." + key + ": " + why);
  };
  if (!std::isfinite(options.cell_size_m) || options.cell_size_m < 0.0)
    fail("cell_size_m", "must be a finite number >= 0");
  if (!std::isfinite(options.disagreement_sigma) || options.disagreement_sigma <= 0.0)
    fail("disagreement_sigma", "must be a finite number > 0");
  if (options.tile_cells < 16) fail("tile_cells", "must be >= 16");
  if (options.min_overlap_cells < 3) fail("min_overlap_cells", "must be >= 3");
  if (!(options.min_information >= 0.0 && options.min_information < 1.0))
    fail("min_information", "must be a number in [0, 1)");
  if (!(options.min_improvement > 0.0 && options.min_improvement <= 1.0))
    fail("min_improvement", "must be a number in (0, 1]");
  if (!(std::isfinite(options.max_correction_m) && options.max_correction_m >= 0.0))
    fail("max_correction_m", "must be a finite number >= 0");
  if (!(std::isfinite(options.max_correction_deg) && options.max_correction_deg >= 0.0))
    fail("max_correction_deg", "must be a finite number >= 0");
  if (!(std::isfinite(options.tilt_sigma_deg) && options.tilt_sigma_deg >= 0.0))
    fail("tilt_sigma_deg", "must be a finite number >= 0");
}

OGRSpatialReference OutputSrs(const MosaicOptions& options, const Input& first) {
  OGRSpatialReference srs;
  if (options.crs.empty()) {
    srs = first.srs;
    if (!srs.IsProjected()) {
      throw io::IoError(first.file.string() + ": its CRS is not projected (a DEM's is UTM or a " +
                        "local projection); set mosaic.crs");
    }
  } else {
    if (srs.SetFromUserInput(options.crs.c_str()) != OGRERR_NONE)
      throw std::invalid_argument("mosaic.crs: GDAL does not read '" + options.crs + "'");
    if (!srs.IsProjected())
      throw std::invalid_argument("mosaic.crs: must be a projected CRS (got '" + options.crs +
                                  "')");
  }
  if (std::abs(srs.GetLinearUnits() - 1.0) > 1e-9)
    throw std::invalid_argument("mosaic.crs: the output CRS must be in metres");
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

// The common grid: the finest input cell (or mosaic.cell_size_m), the union of the footprints,
// its edges on multiples of the cell size so that mosaics of parts share the grid of the whole.
OutputGrid MakeGrid(const std::vector<Input>& inputs, OGRSpatialReference srs,
                    const MosaicOptions& options) {
  OutputGrid grid;
  grid.srs = std::move(srs);
  char* wkt = nullptr;
  grid.srs.exportToWkt(&wkt);
  grid.wkt = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  double cell = options.cell_size_m;
  Eigen::Vector2d min = inputs.front().min_out;
  Eigen::Vector2d max = inputs.front().max_out;
  for (const Input& input : inputs) {
    if (options.cell_size_m == 0.0 && (cell == 0.0 || input.cell_size_out_m < cell))
      cell = input.cell_size_out_m;
    min = min.cwiseMin(input.min_out);
    max = max.cwiseMax(input.max_out);
  }
  // Footprints computed through a CRS transform land a hair off the multiples they are meant
  // to sit on: a millionth of a cell is taken as on.
  constexpr double kSnap = 1e-6;
  const double col0 = std::floor(min.x() / cell + kSnap);
  const double col1 = std::ceil(max.x() / cell - kSnap);
  const double row0 = std::floor(min.y() / cell + kSnap);
  const double row1 = std::ceil(max.y() / cell - kSnap);
  const double width = std::max(1.0, col1 - col0);
  const double height = std::max(1.0, row1 - row0);
  if (width * height > static_cast<double>(std::numeric_limits<int>::max()) * 64.0 ||
      width > std::numeric_limits<int>::max() || height > std::numeric_limits<int>::max()) {
    throw std::invalid_argument("mosaic.cell_size_m: " + std::to_string(cell) +
                                " m gives a grid of " + std::to_string(width) + " x " +
                                std::to_string(height) + " cells, too large");
  }
  grid.width = static_cast<int>(width);
  grid.height = static_cast<int>(height);
  grid.geotransform = {col0 * cell, cell, 0.0, row1 * cell, 0.0, -cell};
  return grid;
}

using io::FailGdalWrite;
using io::TemporaryFile;

// The tiled intermediate GeoTIFF the tiles are written into.
DatasetPtr CreateStaging(const fs::path& staging, const fs::path& out, const OutputGrid& grid,
                         const std::string& datum, std::size_t inputs) {
  DatasetPtr ds = io::CreateStaging(
      staging, out, grid.width, grid.height, grid.geotransform, grid.srs,
      {{"elevation", "m"}, {"elevation_stddev", "m"}, {"count", ""}, {"disagreement", ""}});
  if (!datum.empty()) ds->SetMetadataItem("ELEVATION_DATUM", datum.c_str());
  ds->SetMetadataItem("MOSAIC_INPUTS", std::to_string(inputs).c_str());
  return ds;
}

void WriteTile(GDALDataset* staging, const fs::path& out, const Window& window,
               FusedLayers& fused) {
  std::vector<float>* bands[4] = {&fused.elevation_m, &fused.stddev_m, &fused.count,
                                  &fused.disagreement};
  for (int b = 0; b < 4; ++b) {
    io::WriteWindow(staging, out, b + 1, window.col0, window.row0, window.width, window.height,
                    bands[b]->data());
  }
}

// GDAL as every step uses it: its block cache bounded (when the user set none) and its errors
// kept for our messages rather than printed.
class GdalScope {
 public:
  GdalScope() {
    io::BoundGdalCache();
    CPLPushErrorHandler(CPLQuietErrorHandler);
  }
  ~GdalScope() { CPLPopErrorHandler(); }
  GdalScope(const GdalScope&) = delete;
  GdalScope& operator=(const GdalScope&) = delete;
};

// The inputs opened, checked and placed on the common grid, with their datum offsets: where
// every step starts, before any output exists.
struct Placed {
  std::vector<Input> inputs;
  OutputGrid grid;
};

Placed Place(const std::vector<fs::path>& files, const MosaicOptions& options) {
  CheckOptions(options);
  if (files.empty()) throw std::invalid_argument("mosaic: no input DEM");
  Placed placed;
  for (const fs::path& file : files) placed.inputs.push_back(detail::OpenInput(file));
  std::vector<Input>& inputs = placed.inputs;
  const OGRSpatialReference srs = OutputSrs(options, inputs.front());
  for (Input& input : inputs) detail::LocateInput(&input, srs);
  placed.grid = MakeGrid(inputs, srs, options);
  for (Input& input : inputs) {
    detail::Correction datum;
    datum.datum_offset_m = input.datum_altitude_m - inputs.front().datum_altitude_m;
    detail::SetCorrection(&input, placed.grid.srs, datum);
  }
  return placed;
}

MosaicResult GridResult(const OutputGrid& grid) {
  MosaicResult result;
  result.width = grid.width;
  result.height = grid.height;
  result.geotransform = grid.geotransform;
  result.wkt = grid.wkt;
  result.cell_size_m = grid.cell_size_m();
  return result;
}

// Co-registers the placed inputs in order (each onto the mosaic of those before it).
MosaicPlan Plan(const std::vector<fs::path>& files, Placed* placed, const MosaicOptions& options,
                const registration::RegistrationOptions& registration) {
  std::vector<Input>& inputs = placed->inputs;
  MosaicPlan plan;
  plan.files = files;
  plan.result = GridResult(placed->grid);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    InputReport entry;
    entry.file = inputs[i].file.string();
    entry.reference = i == 0;
    entry.status = i == 0 ? "reference" : "off";
    if (i > 0 && options.coregister) {
      entry = detail::Coregister(inputs, i, placed->grid, options, registration);
    }
    plan.result.inputs.push_back(entry);
  }
  for (const Input& input : inputs) {
    plan.corrections.push_back(input.correction.T.matrix());
    plan.correction_origins.push_back(input.correction.origin);
  }
  return plan;
}

// Fuses the tiles of grid rows [row0, row1) into `staging`, whose first row is grid row `row0`.
// Each tile warps only the inputs that reach it.
void FuseRows(const Placed& placed, int row0, int row1, const MosaicOptions& options,
              GDALDataset* staging, const fs::path& out, MosaicResult* result) {
  const OutputGrid& grid = placed.grid;
  const int tile = options.tile_cells;
  for (int row = row0; row < row1; row += tile) {
    for (int col0 = 0; col0 < grid.width; col0 += tile) {
      const Window window{col0, row, std::min(tile, grid.width - col0), std::min(tile, row1 - row)};
      CellFusion fusion(window.cells());
      for (const Input& input : placed.inputs) {
        if (detail::Touches(input, grid, window))
          fusion.Add(detail::WarpInput(input, grid, window));
      }
      FusedLayers fused = fusion.Finish(options.disagreement_sigma);
      result->valid_cells += fused.valid_cells;
      Window local = window;
      local.row0 -= row0;
      WriteTile(staging, out, local, fused);
      ++result->tiles;
    }
  }
}

// The staged grid as the COG `out`, then the report beside it; both atomically.
void WriteCog(const fs::path& staging, const fs::path& out, const fs::path& report,
              const MosaicResult& result, const MosaicOptions& options) {
  TemporaryFile cog(out, "tmp");
  io::TranslateToCog(staging, cog.path(), out);
  if (report.empty()) {
    cog.CommitTo(out);
    return;
  }
  const fs::path json = io::WriteTemporaryFile(report, MosaicReportJson(result, options));
  try {
    cog.CommitTo(out);
  } catch (...) {
    std::error_code ignored;
    fs::remove(json, ignored);
    throw;
  }
  io::CommitTemporaryFile(json, report);
}

// Re-applies the plan's corrections to freshly placed inputs, after checking they are the ones
// planned. Only corrections co-registration changed are re-applied, so every input ends in the
// very state PlanMosaic left it in.
void ApplyPlan(const MosaicPlan& plan, Placed* placed) {
  const OutputGrid& grid = placed->grid;
  if (grid.width != plan.result.width || grid.height != plan.result.height ||
      grid.geotransform != plan.result.geotransform ||
      plan.corrections.size() != placed->inputs.size() ||
      plan.correction_origins.size() != placed->inputs.size()) {
    throw io::IoError(plan.files.front().string() +
                      ": the inputs are not the ones planned (grid or count changed), or "
                      "mosaic.crs / mosaic.cell_size_m differ from the plan's");
  }
  for (std::size_t i = 0; i < placed->inputs.size(); ++i) {
    Input& input = placed->inputs[i];
    if (plan.corrections[i] == Eigen::Matrix4d::Identity() &&
        plan.correction_origins[i] == Eigen::Vector3d::Zero())
      continue;
    detail::Correction correction = input.correction;  // keeps the datum offset
    correction.T.matrix() = plan.corrections[i];
    correction.origin = plan.correction_origins[i];
    detail::SetCorrection(&input, grid.srs, correction);
  }
}

// A band of whole grid rows as its own grid (a part's GeoTIFF).
OutputGrid RowsOf(const OutputGrid& grid, int row0, int row1) {
  OutputGrid rows = grid;
  rows.height = row1 - row0;
  rows.geotransform[3] = grid.geotransform[3] + row0 * grid.geotransform[5];
  return rows;
}

std::size_t MetadataCount(GDALDataset* ds, const char* key) {
  const char* value = ds->GetMetadataItem(key);
  return value != nullptr ? static_cast<std::size_t>(std::strtoull(value, nullptr, 10)) : 0;
}

Eigen::Matrix4d MatrixFromJson(const nlohmann::json& j) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = j.at(r).at(c).get<double>();
  return m;
}

Eigen::Vector3d VectorFromJson(const nlohmann::json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}

InputReport InputReportFromJson(const nlohmann::json& j) {
  InputReport r;
  r.file = j.at("file").get<std::string>();
  r.reference = j.at("reference").get<bool>();
  r.status = j.at("status").get<std::string>();
  r.reason = j.value("reason", std::string());
  r.overlaps = j.at("overlaps").get<bool>();
  r.applied = j.at("applied").get<bool>();
  r.translation_m = VectorFromJson(j.at("translation_m"));
  r.rotation_deg = VectorFromJson(j.at("rotation_deg"));
  if (j.contains("origin_m")) r.origin_m = VectorFromJson(j.at("origin_m"));
  r.conditioning = j.value("conditioning", 0.0);
  r.unconstrained = j.value("unconstrained", std::string());
  r.overlap_cells = j.at("overlap_cells").get<std::size_t>();
  r.inlier_ratio = j.at("inlier_ratio").get<double>();
  r.iterations = j.at("iterations").get<int>();
  r.disagreement_before = j.at("disagreement_before").get<std::size_t>();
  r.disagreement_after = j.at("disagreement_after").get<std::size_t>();
  r.rms_before_m = j.at("rms_before_m").get<double>();
  r.rms_after_m = j.at("rms_after_m").get<double>();
  return r;
}

constexpr const char* kPlanFormat = "rovermap mosaic plan 1";

}  // namespace

MosaicPlan PlanMosaic(const std::vector<fs::path>& files, const MosaicOptions& options,
                      const registration::RegistrationOptions& registration) {
  const GdalScope gdal;
  Placed placed = Place(files, options);
  return Plan(files, &placed, options, registration);
}

MosaicResult BuildMosaic(const std::vector<fs::path>& files, const fs::path& out,
                         const fs::path& report, const MosaicOptions& options,
                         const registration::RegistrationOptions& registration) {
  const GdalScope gdal;
  Placed placed = Place(files, options);
  MosaicResult result = Plan(files, &placed, options, registration).result;
  TemporaryFile staging(out, "staging");
  DatasetPtr staged = CreateStaging(staging.path(), out, placed.grid,
                                    placed.inputs.front().datum_text, placed.inputs.size());
  FuseRows(placed, 0, placed.grid.height, options, staged.get(), out, &result);
  io::CloseStaging(std::move(staged), out);
  WriteCog(staging.path(), out, report, result, options);
  return result;
}

std::string MosaicPlanJson(const MosaicPlan& plan) {
  nlohmann::json files = nlohmann::json::array();
  for (const fs::path& file : plan.files) files.push_back(file.string());
  nlohmann::json corrections = nlohmann::json::array();
  for (std::size_t i = 0; i < plan.corrections.size(); ++i) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
      rows.push_back({plan.corrections[i](r, 0), plan.corrections[i](r, 1),
                      plan.corrections[i](r, 2), plan.corrections[i](r, 3)});
    }
    const Eigen::Vector3d& o = plan.correction_origins[i];
    corrections.push_back({{"T", rows}, {"origin", {o.x(), o.y(), o.z()}}});
  }
  const nlohmann::json out = {{"format", kPlanFormat},
                              {"files", files},
                              {"wkt", plan.result.wkt},
                              {"corrections", corrections},
                              {"report", nlohmann::json::parse(MosaicReportJson(plan.result, {}))}};
  return out.dump(1) + "\n";
}

MosaicPlan ParseMosaicPlan(const std::string& text, const fs::path& file) {
  MosaicPlan plan;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (j.at("format").get<std::string>() != kPlanFormat)
      throw io::IoError(file.string() + ": not a " + kPlanFormat);
    for (const auto& f : j.at("files")) plan.files.emplace_back(f.get<std::string>());
    for (const auto& c : j.at("corrections")) {
      plan.corrections.push_back(MatrixFromJson(c.at("T")));
      plan.correction_origins.push_back(VectorFromJson(c.at("origin")));
    }
    const nlohmann::json& report = j.at("report");
    plan.result.width = report.at("width").get<int>();
    plan.result.height = report.at("height").get<int>();
    plan.result.cell_size_m = report.at("cell_size_m").get<double>();
    plan.result.geotransform = report.at("geotransform").get<std::array<double, 6>>();
    plan.result.wkt = j.at("wkt").get<std::string>();
    for (const auto& input : report.at("inputs"))
      plan.result.inputs.push_back(InputReportFromJson(input));
  } catch (const nlohmann::json::exception& e) {
    throw io::IoError(file.string() + ": not a mosaic plan (" + e.what() + ")");
  }
  if (plan.files.empty() || plan.corrections.size() != plan.files.size() ||
      plan.result.inputs.size() != plan.files.size()) {
    throw io::IoError(file.string() +
                      ": not a mosaic plan (counts of files, corrections and "
                      "reports differ)");
  }
  return plan;
}

std::pair<int, int> MosaicPartRows(const MosaicPlan& plan, int part, int parts,
                                   const MosaicOptions& options) {
  if (parts < 1 || part < 0 || part >= parts)
    throw std::invalid_argument("mosaic part " + std::to_string(part) + " of " +
                                std::to_string(parts) + ": not a part");
  const long tile = options.tile_cells;
  const long tile_rows = (plan.result.height + tile - 1) / tile;
  const long first = tile_rows * part / parts;
  const long last = tile_rows * (part + 1) / parts;
  return {static_cast<int>(std::min<long>(first * tile, plan.result.height)),
          static_cast<int>(std::min<long>(last * tile, plan.result.height))};
}

void FuseMosaicPart(const MosaicPlan& plan, int part, int parts, const fs::path& out,
                    const MosaicOptions& options) {
  const auto [row0, row1] = MosaicPartRows(plan, part, parts, options);
  if (row0 == row1) return;
  const GdalScope gdal;
  Placed placed = Place(plan.files, options);
  ApplyPlan(plan, &placed);
  MosaicResult counts;
  TemporaryFile temp(out, "tmp");
  DatasetPtr staged = CreateStaging(temp.path(), out, RowsOf(placed.grid, row0, row1),
                                    placed.inputs.front().datum_text, placed.inputs.size());
  FuseRows(placed, row0, row1, options, staged.get(), out, &counts);
  staged->SetMetadataItem("MOSAIC_TILES", std::to_string(counts.tiles).c_str());
  staged->SetMetadataItem("MOSAIC_VALID_CELLS", std::to_string(counts.valid_cells).c_str());
  io::CloseStaging(std::move(staged), out);
  temp.CommitTo(out);
}

MosaicResult AssembleMosaic(const MosaicPlan& plan, int parts,
                            const std::function<fs::path(int)>& part_file, const fs::path& out,
                            const fs::path& report, const MosaicOptions& options) {
  const GdalScope gdal;
  Placed placed = Place(plan.files, options);
  ApplyPlan(plan, &placed);
  const OutputGrid& grid = placed.grid;
  MosaicResult result = plan.result;
  TemporaryFile staging(out, "staging");
  DatasetPtr staged = CreateStaging(staging.path(), out, grid, placed.inputs.front().datum_text,
                                    placed.inputs.size());
  std::vector<float> buffer;
  for (int part = 0; part < parts; ++part) {
    const auto [row0, row1] = MosaicPartRows(plan, part, parts, options);
    if (row0 == row1) continue;
    const fs::path file = part_file(part);
    DatasetPtr ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    if (!ds) throw io::IoError(file.string() + ": missing or not a GeoTIFF (mosaic part)");
    if (ds->GetRasterXSize() != grid.width || ds->GetRasterYSize() != row1 - row0 ||
        ds->GetRasterCount() != 4) {
      throw io::IoError(file.string() + ": not part " + std::to_string(part) + " of " +
                        std::to_string(parts) + " of this plan (size or bands differ)");
    }
    result.tiles += static_cast<int>(MetadataCount(ds.get(), "MOSAIC_TILES"));
    result.valid_cells += MetadataCount(ds.get(), "MOSAIC_VALID_CELLS");
    // A band of tile rows at a time: memory bounded by a tile row, not the part.
    const int chunk = options.tile_cells;
    for (int row = row0; row < row1; row += chunk) {
      const int rows = std::min(chunk, row1 - row);
      buffer.resize(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(rows));
      for (int b = 1; b <= 4; ++b) {
        if (ds->GetRasterBand(b)->RasterIO(GF_Read, 0, row - row0, grid.width, rows, buffer.data(),
                                           grid.width, rows, GDT_Float32, 0, 0,
                                           nullptr) != CE_None) {
          throw io::IoError(file.string() + ": cannot read it (mosaic part)");
        }
        if (staged->GetRasterBand(b)->RasterIO(GF_Write, 0, row, grid.width, rows, buffer.data(),
                                               grid.width, rows, GDT_Float32, 0, 0,
                                               nullptr) != CE_None) {
          FailGdalWrite(out, "cannot write a tile");
        }
      }
    }
  }
  io::CloseStaging(std::move(staged), out);
  WriteCog(staging.path(), out, report, result, options);
  return result;
}

fs::path MosaicReportPath(const fs::path& out) { return fs::path(out).replace_extension(".json"); }

std::string MosaicReportJson(const MosaicResult& result, const MosaicOptions& options) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const InputReport& r : result.inputs) {
    inputs.push_back(
        {{"file", r.file},
         {"reference", r.reference},
         {"status", r.status},
         {"reason", r.reason},
         {"overlaps", r.overlaps},
         {"applied", r.applied},
         {"translation_m", {r.translation_m.x(), r.translation_m.y(), r.translation_m.z()}},
         {"rotation_deg", {r.rotation_deg.x(), r.rotation_deg.y(), r.rotation_deg.z()}},
         {"origin_m", {r.origin_m.x(), r.origin_m.y(), r.origin_m.z()}},
         {"conditioning", r.conditioning},
         {"unconstrained", r.unconstrained},
         {"overlap_cells", r.overlap_cells},
         {"inlier_ratio", r.inlier_ratio},
         {"iterations", r.iterations},
         {"disagreement_before", r.disagreement_before},
         {"disagreement_after", r.disagreement_after},
         {"rms_before_m", r.rms_before_m},
         {"rms_after_m", r.rms_after_m}});
  }
  const nlohmann::json out = {{"width", result.width},
                              {"height", result.height},
                              {"cell_size_m", result.cell_size_m},
                              {"geotransform", result.geotransform},
                              {"tiles", result.tiles},
                              {"valid_cells", result.valid_cells},
                              {"options",
                               {{"crs", options.crs},
                                {"cell_size_m", options.cell_size_m},
                                {"disagreement_sigma", options.disagreement_sigma},
                                {"tile_cells", options.tile_cells},
                                {"coregister", options.coregister},
                                {"min_overlap_cells", options.min_overlap_cells},
                                {"min_information", options.min_information},
                                {"min_improvement", options.min_improvement},
                                {"max_correction_m", options.max_correction_m},
                                {"max_correction_deg", options.max_correction_deg},
                                {"tilt_sigma_deg", options.tilt_sigma_deg}}},
                              {"inputs", inputs}};
  return out.dump(2) + "\n";
}

}  // namespace rovermap::mosaic
