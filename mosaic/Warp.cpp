#include "mosaic/Warp.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdalwarper.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <system_error>

#include "io/IoError.hpp"

namespace rovermap::mosaic::detail {
namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void RegisterGdal() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

std::string LastGdalError() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg != nullptr && *msg != '\0') ? std::string(" (") + msg + ")" : std::string();
}

[[noreturn]] void Fail(const fs::path& file, const std::string& what) {
  throw io::IoError(file.string() + ": " + what + LastGdalError());
}

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* ct) const {
    OGRCoordinateTransformation::DestroyCT(ct);
  }
};
using TransformPtr = std::unique_ptr<OGRCoordinateTransformation, TransformDeleter>;

TransformPtr MakeTransform(const Input& input, const OGRSpatialReference& srs) {
  TransformPtr ct(OGRCreateCoordinateTransformation(&input.srs, &srs));
  if (!ct) Fail(input.file, "no transformation from its CRS to the mosaic's");
  return ct;
}

Eigen::Vector2d PixelToCrs(const std::array<double, 6>& g, double u, double v) {
  return {g[0] + u * g[1] + v * g[2], g[3] + u * g[4] + v * g[5]};
}

// "height above the origin altitude 123.000000 m (world z, ENU up)" -> 123 (io::WriteDemGeoTiff).
double DatumAltitude(const std::string& text) {
  const std::string marker = "origin altitude ";
  const std::size_t at = text.find(marker);
  if (at == std::string::npos) return 0.0;
  return std::strtod(text.c_str() + at + marker.size(), nullptr);
}

// One pass of GDAL's warper from `src` bands onto `dst` bands; NaN is no data on both sides.
void Warp(const Input& input, GDALDataset* src, GDALDataset* dst, const std::vector<int>& src_bands,
          const std::vector<int>& dst_bands, GDALResampleAlg algorithm) {
  GDALWarpOptions* options = GDALCreateWarpOptions();
  const int n = static_cast<int>(src_bands.size());
  options->hSrcDS = GDALDataset::ToHandle(src);
  options->hDstDS = GDALDataset::ToHandle(dst);
  options->nBandCount = n;
  options->panSrcBands = static_cast<int*>(CPLMalloc(sizeof(int) * n));
  options->panDstBands = static_cast<int*>(CPLMalloc(sizeof(int) * n));
  options->padfSrcNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double) * n));
  options->padfDstNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double) * n));
  for (int b = 0; b < n; ++b) {
    options->panSrcBands[b] = src_bands[b];
    options->panDstBands[b] = dst_bands[b];
    options->padfSrcNoDataReal[b] = kNaN;
    options->padfDstNoDataReal[b] = kNaN;
  }
  options->eResampleAlg = algorithm;
  options->eWorkingDataType = GDT_Float32;
  options->papszWarpOptions = CSLSetNameValue(options->papszWarpOptions, "INIT_DEST", "NO_DATA");
  // The exact transformer (no approximation): a grid of partial mosaics resamples to itself.
  options->pTransformerArg =
      GDALCreateGenImgProjTransformer2(options->hSrcDS, options->hDstDS, nullptr);
  if (options->pTransformerArg == nullptr) {
    GDALDestroyWarpOptions(options);
    Fail(input.file, "GDAL cannot transform it onto the mosaic grid");
  }
  options->pfnTransformer = GDALGenImgProjTransform;
  GDALWarpOperation operation;
  CPLErr error = operation.Initialize(options);
  if (error == CE_None) {
    error = operation.ChunkAndWarpImage(0, 0, dst->GetRasterXSize(), dst->GetRasterYSize());
  }
  GDALDestroyGenImgProjTransformer(options->pTransformerArg);
  GDALDestroyWarpOptions(options);
  if (error != CE_None) Fail(input.file, "GDAL's warper failed");
}

}  // namespace

Window OutputGrid::Cover(const Eigen::Vector2d& min, const Eigen::Vector2d& max) const {
  const double s = cell_size_m();
  const int col0 = std::max(0, static_cast<int>(std::floor((min.x() - geotransform[0]) / s)));
  const int col1 = std::min(width, static_cast<int>(std::ceil((max.x() - geotransform[0]) / s)));
  const int row0 = std::max(0, static_cast<int>(std::floor((geotransform[3] - max.y()) / s)));
  const int row1 = std::min(height, static_cast<int>(std::ceil((geotransform[3] - min.y()) / s)));
  if (col1 <= col0 || row1 <= row0) return {};
  return {col0, row0, col1 - col0, row1 - row0};
}

Input OpenInput(const fs::path& file) {
  RegisterGdal();
  CPLErrorReset();
  std::error_code error;
  const fs::file_status status = fs::status(file, error);
  if (status.type() == fs::file_type::not_found)
    throw io::IoError(file.string() + ": no such file");
  // Not "no such file": it may be there, in a directory we may not enter.
  if (error) throw io::IoError(file.string() + ": cannot access (" + error.message() + ")");
  if (fs::is_directory(status)) throw io::IoError(file.string() + ": a directory, not a DEM");
  if (fs::is_regular_file(status) && fs::file_size(file, error) == 0)
    throw io::IoError(file.string() + ": empty file");
  const char* const drivers[] = {"GTiff", "COG", nullptr};
  Input input;
  input.file = file;
  input.dataset.reset(GDALDataset::FromHandle(
      GDALOpenEx(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, nullptr)));
  if (!input.dataset) Fail(file, "not a GeoTIFF");
  GDALDataset& ds = *input.dataset;
  const int bands = ds.GetRasterCount();
  if (bands < 3) {
    throw io::IoError(file.string() + ": has " + std::to_string(bands) +
                      " band(s); a DEM has 3 (elevation m, sigma m, point count)");
  }
  auto& g = input.geotransform;
  if (ds.GetGeoTransform(g.data()) != CE_None) Fail(file, "has no geotransform");
  if (g[1] * g[5] - g[2] * g[4] == 0.0) Fail(file, "has a degenerate geotransform");
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  if (srs == nullptr || srs->IsEmpty()) Fail(file, "has no CRS");
  input.srs = *srs;
  input.srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  input.is_mosaic =
      bands >= 4 && std::string(ds.GetRasterBand(4)->GetDescription()) == "disagreement";
  if (const char* datum = ds.GetMetadataItem("ELEVATION_DATUM")) input.datum_text = datum;
  input.datum_altitude_m = DatumAltitude(input.datum_text);
  input.warp_geotransform = g;
  return input;
}

void LocateInput(Input* input, const OGRSpatialReference& srs) {
  const TransformPtr ct = MakeTransform(*input, srs);
  const double w = input->dataset->GetRasterXSize();
  const double h = input->dataset->GetRasterYSize();
  // The outline, densely sampled: a reprojected edge is curved.
  constexpr int kSteps = 32;
  std::vector<double> xs;
  std::vector<double> ys;
  for (int k = 0; k <= kSteps; ++k) {
    const double f = static_cast<double>(k) / kSteps;
    for (const auto& [u, v] :
         {std::pair{f * w, 0.0}, std::pair{f * w, h}, std::pair{0.0, f * h}, std::pair{w, f * h}}) {
      const Eigen::Vector2d p = PixelToCrs(input->geotransform, u, v);
      xs.push_back(p.x());
      ys.push_back(p.y());
    }
  }
  std::vector<int> ok(xs.size(), 0);
  ct->Transform(static_cast<int>(xs.size()), xs.data(), ys.data(), nullptr, ok.data());
  bool any = false;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (ok[i] == 0) continue;
    if (!any) input->min_out = input->max_out = {xs[i], ys[i]};
    input->min_out = input->min_out.cwiseMin(Eigen::Vector2d(xs[i], ys[i]));
    input->max_out = input->max_out.cwiseMax(Eigen::Vector2d(xs[i], ys[i]));
    any = true;
  }
  if (!any) Fail(input->file, "its footprint cannot be transformed into the mosaic's CRS");
  // Cell edge in the output CRS: the square root of a centre cell's area, transformed when the
  // CRS differ.
  const auto& g = input->geotransform;
  if (input->srs.IsSame(&srs)) {
    input->cell_size_out_m = std::sqrt(std::abs(g[1] * g[5] - g[2] * g[4]));
    return;
  }
  double cx[3];
  double cy[3];
  const Eigen::Vector2d uv[3] = {{w / 2, h / 2}, {w / 2 + 1, h / 2}, {w / 2, h / 2 + 1}};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d p = PixelToCrs(input->geotransform, uv[k].x(), uv[k].y());
    cx[k] = p.x();
    cy[k] = p.y();
  }
  int cell_ok[3] = {0, 0, 0};
  ct->Transform(3, cx, cy, nullptr, cell_ok);
  if (!cell_ok[0] || !cell_ok[1] || !cell_ok[2])
    Fail(input->file, "its cells cannot be transformed");
  const double area =
      std::abs((cx[1] - cx[0]) * (cy[2] - cy[0]) - (cy[1] - cy[0]) * (cx[2] - cx[0]));
  input->cell_size_out_m = std::sqrt(area);
}

void SetCorrection(Input* input, const OGRSpatialReference& srs, const Correction& correction) {
  input->correction = correction;
  // f: input CRS -> output CRS, linearised at the footprint's centre c: f(q) ≈ f(c) + J (q − c).
  const TransformPtr ct = MakeTransform(*input, srs);
  const auto& g = input->geotransform;
  const double w = input->dataset->GetRasterXSize();
  const double h = input->dataset->GetRasterYSize();
  const Eigen::Vector2d c = PixelToCrs(g, w / 2, h / 2);
  const double step = std::hypot(g[1], g[4]);
  double xs[3] = {c.x(), c.x() + step, c.x()};
  double ys[3] = {c.y(), c.y(), c.y() + step};
  int ok[3] = {0, 0, 0};
  ct->Transform(3, xs, ys, nullptr, ok);
  if (!ok[0] || !ok[1] || !ok[2]) Fail(input->file, "its centre cannot be transformed");
  const Eigen::Vector2d fc(xs[0], ys[0]);
  Eigen::Matrix2d J;
  J << (xs[1] - xs[0]) / step, (xs[2] - xs[0]) / step, (ys[1] - ys[0]) / step,
      (ys[2] - ys[0]) / step;
  // The correction's horizontal part in the output CRS: A(p) = R2 (p − o) + o + t.
  const Eigen::Matrix2d R2 = correction.T.linear().topLeftCorner<2, 2>();
  const Eigen::Vector2d o = correction.origin.head<2>();
  const Eigen::Vector2d t = correction.T.translation().head<2>();
  // In the input CRS: q -> c + J⁻¹ (A(f(c) + J (q − c)) − f(c)) = M q + b.
  const Eigen::Matrix2d J_inv = J.inverse();
  const Eigen::Matrix2d M = J_inv * R2 * J;
  const Eigen::Vector2d b = c + J_inv * (R2 * (fc - o) + o + t - fc) - M * c;
  // The new geotransform: pixel (u, v) -> M (q0 + G (u, v)) + b.
  const Eigen::Vector2d q0(g[0], g[3]);
  Eigen::Matrix2d G;
  G << g[1], g[2], g[4], g[5];
  const Eigen::Vector2d q0_new = M * q0 + b;
  const Eigen::Matrix2d G_new = M * G;
  input->warp_geotransform = {q0_new.x(), G_new(0, 0), G_new(0, 1),
                              q0_new.y(), G_new(1, 0), G_new(1, 1)};
}

bool Touches(const Input& input, const OutputGrid& grid, const Window& window) {
  const double margin = 2.0 * std::max(grid.cell_size_m(), input.cell_size_out_m) +
                        input.correction.T.translation().head<2>().norm();
  const Eigen::Vector2d top_left = grid.CellCentre(window.col0, window.row0);
  const Eigen::Vector2d bottom_right =
      grid.CellCentre(window.col0 + window.width - 1, window.row0 + window.height - 1);
  return input.min_out.x() - margin <= bottom_right.x() &&
         input.max_out.x() + margin >= top_left.x() && input.min_out.y() - margin <= top_left.y() &&
         input.max_out.y() + margin >= bottom_right.y();
}

WarpedLayers WarpInput(const Input& input, const OutputGrid& grid, const Window& window) {
  RegisterGdal();
  CPLErrorReset();
  // The input seen through a VRT with the corrected geotransform: the file stays as it is.
  GDALDriver* vrt_driver = GetGDALDriverManager()->GetDriverByName("VRT");
  GDALDriver* mem_driver = GetGDALDriverManager()->GetDriverByName("MEM");
  if (vrt_driver == nullptr || mem_driver == nullptr) Fail(input.file, "GDAL lacks VRT or MEM");
  DatasetPtr source(
      vrt_driver->CreateCopy("", input.dataset.get(), FALSE, nullptr, nullptr, nullptr));
  if (!source) Fail(input.file, "cannot be opened as a VRT");
  std::array<double, 6> g = input.warp_geotransform;
  source->SetGeoTransform(g.data());

  const int bands = input.is_mosaic ? 4 : 3;
  DatasetPtr target(
      mem_driver->Create("", window.width, window.height, bands, GDT_Float32, nullptr));
  if (!target) Fail(input.file, "cannot allocate a tile");
  std::array<double, 6> tile = grid.geotransform;
  tile[0] += window.col0 * grid.geotransform[1];
  tile[3] += window.row0 * grid.geotransform[5];
  target->SetGeoTransform(tile.data());
  target->SetSpatialRef(&grid.srs);

  // Elevation and σ bilinearly (a smooth surface, no half-cell steps: co-registration and
  // the fused heights see sub-cell shifts); count and disagreement by nearest neighbour (they
  // are counts: a blend of 3 and 4 points is no count).
  Warp(input, source.get(), target.get(), {1, 2}, {1, 2}, GRA_Bilinear);
  if (input.is_mosaic) {
    Warp(input, source.get(), target.get(), {3, 4}, {3, 4}, GRA_NearestNeighbour);
  } else {
    Warp(input, source.get(), target.get(), {3}, {3}, GRA_NearestNeighbour);
  }

  WarpedLayers layers;
  std::vector<float>* outputs[4] = {&layers.elevation_m, &layers.stddev_m, &layers.count,
                                    &layers.disagreement};
  for (int b = 0; b < bands; ++b) {
    outputs[b]->resize(window.cells());
    if (target->GetRasterBand(b + 1)->RasterIO(GF_Read, 0, 0, window.width, window.height,
                                               outputs[b]->data(), window.width, window.height,
                                               GDT_Float32, 0, 0, nullptr) != CE_None) {
      Fail(input.file, "cannot read a warped tile");
    }
  }

  // Heights: the datum shift and the correction's vertical part,
  // z' = o_z + R[2,:]·(p − o) + t_z, at the output cell's position (the cell the point lands in:
  // the difference to its source position, a correction's few decimetres times a tilt of
  // milliradians, is below a millimetre).
  const Correction& k = input.correction;
  const Eigen::Vector3d r = k.T.linear().row(2);
  const double t_z = k.T.translation().z();
  for (int row = 0; row < window.height; ++row) {
    for (int col = 0; col < window.width; ++col) {
      float& z = layers.elevation_m[static_cast<std::size_t>(row) * window.width + col];
      if (!std::isfinite(z)) continue;
      const Eigen::Vector2d xy = grid.CellCentre(window.col0 + col, window.row0 + row);
      const Eigen::Vector3d p(xy.x(), xy.y(), z + k.datum_offset_m);
      const Eigen::Vector3d d = p - k.origin;
      z = static_cast<float>(k.origin.z() + r.dot(d) + t_z);
    }
  }
  return layers;
}

}  // namespace rovermap::mosaic::detail
