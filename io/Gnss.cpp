#include "io/Gnss.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

std::string Trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

}  // namespace

std::vector<GnssFix> ParseGnssCsv(std::string_view text, const std::filesystem::path& path) {
  std::vector<GnssFix> fixes;
  bool header = false;
  int line_number = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    ++line_number;
    std::string line(text.substr(start, end - start));
    start = end + 1;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    line = Trimmed(line);
    if (line.empty()) {
      if (end == text.size()) break;
      continue;
    }
    const std::string where = path.string() + ":" + std::to_string(line_number) + ": ";
    if (!header) {
      if (line != kGnssCsvHeader)
        throw IoError(where + "expected the header '" + std::string(kGnssCsvHeader) + "'");
      header = true;
      continue;
    }
    double v[7];
    int count = 0;
    std::size_t i = 0;
    while (true) {
      const std::size_t comma = line.find(',', i);
      const std::string field =
          Trimmed(line.substr(i, comma == std::string::npos ? std::string::npos : comma - i));
      if (count == 7)
        throw IoError(where + "more than 7 columns (" + std::string(kGnssCsvHeader) + ")");
      double value = 0.0;
      const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
      if (field.empty() || ec != std::errc() || ptr != field.data() + field.size() ||
          !std::isfinite(value))
        throw IoError(where + "not a finite number '" + field + "'");
      v[count++] = value;
      if (comma == std::string::npos) break;
      i = comma + 1;
    }
    if (count != 7)
      throw IoError(where + std::to_string(count) + " columns, expected 7 (" +
                    std::string(kGnssCsvHeader) + ")");
    if (std::abs(v[1]) > 90.0) throw IoError(where + "latitude out of [-90, 90]");
    if (std::abs(v[2]) > 180.0) throw IoError(where + "longitude out of [-180, 180]");
    if (!(v[4] > 0.0 && v[5] > 0.0 && v[6] > 0.0)) throw IoError(where + "a sigma is not > 0");
    if (!fixes.empty() && !(v[0] > fixes.back().timestamp))
      throw IoError(where + "timestamp " + std::to_string(v[0]) +
                    " is not after the previous one (line " + std::to_string(fixes.back().line) +
                    ")");
    GnssFix f;
    f.timestamp = v[0];
    f.latitude_deg = v[1];
    f.longitude_deg = v[2];
    f.altitude_m = v[3];
    f.sigma_enu_m = Eigen::Vector3d(v[4], v[5], v[6]);
    f.line = line_number;
    fixes.push_back(f);
    if (end == text.size()) break;
  }
  if (!header)
    throw IoError(path.string() + ": empty, expected the header '" + std::string(kGnssCsvHeader) +
                  "'");
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
