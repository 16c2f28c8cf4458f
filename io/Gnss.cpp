#include "io/Gnss.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/detail/TextParse.hpp"

namespace rovermap::io {
namespace {

std::string_view Trimmed(std::string_view s) {
  while (!s.empty() && detail::IsBlank(s.back())) s.remove_suffix(1);
  while (!s.empty() && detail::IsBlank(s.front())) s.remove_prefix(1);
  return s;
}

}  // namespace

std::vector<GnssFix> ParseGnssCsv(std::string_view text, const std::filesystem::path& path) {
  std::vector<GnssFix> fixes;
  bool header = false;
  detail::LineCursor cursor(text);
  for (std::string_view raw; cursor.Next(&raw);) {
    const std::string_view line = Trimmed(detail::StripComment(raw));
    if (line.empty()) continue;
    const std::size_t n = cursor.LineNumber();
    if (!header) {
      if (line != kGnssCsvHeader)
        detail::Fail(path, n, "expected the header '" + std::string(kGnssCsvHeader) + "'");
      header = true;
      continue;
    }
    double v[7];
    int count = 0;
    for (std::size_t i = 0;;) {
      const std::size_t comma = line.find(',', i);
      const std::string_view field =
          Trimmed(line.substr(i, comma == std::string_view::npos ? comma : comma - i));
      if (count == 7)
        detail::Fail(path, n, "more than 7 columns (" + std::string(kGnssCsvHeader) + ")");
      if (detail::ParseDouble(field, &v[count]) != detail::NumberStatus::kOk ||
          !std::isfinite(v[count]))
        detail::Fail(path, n, "not a finite number " + detail::Quote(field));
      ++count;
      if (comma == std::string_view::npos) break;
      i = comma + 1;
    }
    if (count != 7)
      detail::Fail(
          path, n,
          std::to_string(count) + " columns, expected 7 (" + std::string(kGnssCsvHeader) + ")");
    if (std::abs(v[1]) > 90.0) detail::Fail(path, n, "latitude out of [-90, 90]");
    if (std::abs(v[2]) > 180.0) detail::Fail(path, n, "longitude out of [-180, 180]");
    if (!(v[4] > 0.0 && v[5] > 0.0 && v[6] > 0.0)) detail::Fail(path, n, "a sigma is not > 0");
    if (!fixes.empty() && !(v[0] > fixes.back().timestamp))
      detail::Fail(path, n,
                   "timestamp " + std::to_string(v[0]) + " is not after the previous one (line " +
                       std::to_string(fixes.back().line) + ")");
    GnssFix f;
    f.timestamp = v[0];
    f.latitude_deg = v[1];
    f.longitude_deg = v[2];
    f.altitude_m = v[3];
    f.sigma_enu_m = Eigen::Vector3d(v[4], v[5], v[6]);
    f.line = static_cast<int>(n);
    fixes.push_back(f);
  }
  if (!header)
    detail::Fail(path, 0, "empty, expected the header '" + std::string(kGnssCsvHeader) + "'");
  return fixes;
}

std::vector<GnssFix> ReadGnssCsv(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": cannot read");
  return ParseGnssCsv(text.str(), path);
}

void WriteGnssCsv(const std::filesystem::path& path, const std::vector<GnssFix>& fixes) {
  std::ostringstream s;
  s << kGnssCsvHeader << '\n' << std::setprecision(17);
  for (const GnssFix& f : fixes) {
    s << f.timestamp << ',' << f.latitude_deg << ',' << f.longitude_deg << ',' << f.altitude_m
      << ',' << f.sigma_enu_m.x() << ',' << f.sigma_enu_m.y() << ',' << f.sigma_enu_m.z() << '\n';
  }
  WriteFileAtomically(path, s.str());
}

}  // namespace rovermap::io
