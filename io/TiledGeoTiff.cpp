#include "io/TiledGeoTiff.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <initializer_list>
#include <limits>
#include <mutex>
#include <system_error>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

// A GDAL option list (free with CSLDestroy).
char** CreationOptions(std::initializer_list<std::pair<const char*, const char*>> options) {
  char** list = nullptr;
  for (const auto& [name, value] : options) list = CSLSetNameValue(list, name, value);
  return list;
}

}  // namespace

void RegisterGdal() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

void BoundGdalCache() {
  constexpr GIntBig kCacheBytes = GIntBig{64} << 20;
  if (CPLGetConfigOption("GDAL_CACHEMAX", nullptr) == nullptr) GDALSetCacheMax64(kCacheBytes);
}

QuietGdal::QuietGdal() {
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
}

QuietGdal::~QuietGdal() { CPLPopErrorHandler(); }

std::string QuietGdal::Last() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg != nullptr && *msg != '\0') ? std::string(" (") + msg + ")" : std::string();
}

void GdalDatasetCloser::operator()(GDALDataset* ds) const {
  if (ds != nullptr) GDALClose(GDALDataset::ToHandle(ds));
}

TemporaryFile::TemporaryFile(const fs::path& out, const std::string& tag) {
  std::string pattern =
      (out.parent_path() / ("." + out.filename().string() + "." + tag + "-XXXXXX")).string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0) {
    throw IoError(out.string() + ": cannot create a temporary file beside it (" +
                  std::generic_category().message(errno) + ")");
  }
  // mkstemp makes the file 0600: the output gets the mode any new file would (0666 less the
  // umask), as the other outputs.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  ::close(fd);
  path_ = pattern;
}

TemporaryFile::~TemporaryFile() {
  if (!path_.empty()) {
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
}

void TemporaryFile::CommitTo(const fs::path& out) {
  const fs::path temp = path_;
  path_.clear();
  CommitTemporaryFile(temp, out);
}

void FailGdalWrite(const fs::path& out, const std::string& what) {
  const char* msg = CPLGetLastErrorMsg();
  throw IoError(out.string() + ": " + what +
                (msg != nullptr && *msg != '\0' ? std::string(" (") + msg + ")" : ""));
}

GdalDatasetPtr CreateStaging(const fs::path& staging, const fs::path& out, int width, int height,
                             const std::array<double, 6>& geotransform,
                             const OGRSpatialReference& srs, const std::vector<StagedBand>& bands) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (gtiff == nullptr) FailGdalWrite(out, "GDAL lacks the GTiff driver");
  char** create = CreationOptions({{"TILED", "YES"},
                                   {"BLOCKXSIZE", "256"},
                                   {"BLOCKYSIZE", "256"},
                                   {"COMPRESS", "DEFLATE"},
                                   {"PREDICTOR", "3"},
                                   {"ZLEVEL", "1"},
                                   {"BIGTIFF", "IF_SAFER"},
                                   {"SPARSE_OK", "TRUE"}});
  GdalDatasetPtr ds(gtiff->Create(staging.c_str(), width, height, static_cast<int>(bands.size()),
                                  GDT_Float32, create));
  CSLDestroy(create);
  if (!ds) FailGdalWrite(out, "cannot create the staging GeoTIFF");
  std::array<double, 6> g = geotransform;
  ds->SetGeoTransform(g.data());
  ds->SetSpatialRef(&srs);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBand* band = ds->GetRasterBand(static_cast<int>(b) + 1);
    band->SetDescription(bands[b].name.c_str());
    if (!bands[b].unit.empty()) band->SetUnitType(bands[b].unit.c_str());
    band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  }
  return ds;
}

void WriteWindow(GDALDataset* staging, const fs::path& out, int band, int col0, int row0, int width,
                 int height, const float* data) {
  if (staging->GetRasterBand(band)->RasterIO(GF_Write, col0, row0, width, height,
                                             const_cast<float*>(data), width, height, GDT_Float32,
                                             0, 0, nullptr) != CE_None) {
    FailGdalWrite(out, "cannot write a tile");
  }
}

void CloseStaging(GdalDatasetPtr staged, const fs::path& out) {
  CPLErrorReset();
  GDALDataset* raw = staged.release();
  GDALClose(GDALDataset::ToHandle(raw));
  if (CPLGetLastErrorType() >= CE_Failure) FailGdalWrite(out, "cannot finish the staging GeoTIFF");
}

void TranslateToCog(const fs::path& staging, const fs::path& cog, const fs::path& out,
                    const char* resampling) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("COG");
  if (driver == nullptr) FailGdalWrite(out, "GDAL lacks the COG driver");
  GdalDatasetPtr source(GDALDataset::Open(staging.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!source) FailGdalWrite(out, "cannot reopen the staging GeoTIFF");
  char** create = CreationOptions({{"COMPRESS", "DEFLATE"},
                                   {"PREDICTOR", "FLOATING_POINT"},
                                   {"LEVEL", "1"},
                                   {"BLOCKSIZE", "512"},
                                   {"OVERVIEWS", "AUTO"},
                                   {"RESAMPLING", resampling},
                                   {"BIGTIFF", "IF_SAFER"},
                                   {"NUM_THREADS", "2"}});
  CPLErrorReset();
  GDALDataset* copy =
      driver->CreateCopy(cog.c_str(), source.get(), FALSE, create, nullptr, nullptr);
  CSLDestroy(create);
  bool ok = copy != nullptr && CPLGetLastErrorType() < CE_Failure;
  if (copy != nullptr) GDALClose(GDALDataset::ToHandle(copy));
  ok = ok && CPLGetLastErrorType() < CE_Failure;
  if (!ok) FailGdalWrite(out, "GDAL cannot write the COG");
  // On disk before the rename, as WriteFileAtomically does.
  const int fd = ::open(cog.c_str(), O_RDONLY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!synced) {
    throw IoError(out.string() + ": cannot flush the COG to disk (" +
                  std::generic_category().message(errno) + ")");
  }
}

}  // namespace rovermap::io
