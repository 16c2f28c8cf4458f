// gnss.csv (io/Gnss): what it accepts, what it refuses and where, and the fixes' place in the
// world frame (Georeference::GeodeticToEnu against GeographicLib's inverse).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "io/Georeference.hpp"
#include "io/Gnss.hpp"
#include "io/IoError.hpp"
#include "tests/support/ScratchDir.hpp"

using namespace rovermap;

namespace {

const std::string kHeader = std::string(io::kGnssCsvHeader) + "\n";

std::string ErrorOf(const std::string& text) {
  try {
    io::ParseGnssCsv(text, "seq/gnss.csv");
  } catch (const io::IoError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(GnssCsv, ReadsFixesWithCommentsAndCrlf) {
  const auto fixes = io::ParseGnssCsv("# a receiver's log\r\n" + kHeader +
                                          "0.5, 46.5, 6.5, 400.25, 0.3, 0.4, 0.9\r\n\n" +
                                          "1.5,46.6,6.6,401,0.3,0.4,0.9 # trailing\n",
                                      "gnss.csv");
  ASSERT_EQ(fixes.size(), 2u);
  EXPECT_DOUBLE_EQ(fixes[0].timestamp, 0.5);
  EXPECT_DOUBLE_EQ(fixes[0].altitude_m, 400.25);
  EXPECT_EQ(fixes[0].sigma_enu_m, Eigen::Vector3d(0.3, 0.4, 0.9));
  EXPECT_EQ(fixes[0].line, 3);
  EXPECT_EQ(fixes[1].line, 5);
}

TEST(GnssCsv, WritesWhatItReadsBitForBit) {
  io::GnssFix f;
  f.timestamp = 12.345678901234;
  f.latitude_deg = 46.519100000000002;
  f.longitude_deg = 6.5667999999999997;
  f.altitude_m = 400.10463581420919;
  f.sigma_enu_m = Eigen::Vector3d(0.5, 0.5, 1.0);
  const std::filesystem::path path = rovermap::testing::ScratchDir() / "gnss.csv";
  io::WriteGnssCsv(path, {f});
  const auto back = io::ReadGnssCsv(path);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].timestamp, f.timestamp);
  EXPECT_EQ(back[0].latitude_deg, f.latitude_deg);
  EXPECT_EQ(back[0].longitude_deg, f.longitude_deg);
  EXPECT_EQ(back[0].altitude_m, f.altitude_m);
  EXPECT_EQ(back[0].sigma_enu_m, f.sigma_enu_m);
}

TEST(GnssCsv, BadFilesAreRefusedNamingTheLine) {
  EXPECT_NE(ErrorOf("").find("seq/gnss.csv: empty"), std::string::npos) << ErrorOf("");
  EXPECT_NE(ErrorOf("t,lat,lon\n").find("seq/gnss.csv:1: expected the header"), std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,46,6,400,0.5,0.5\n").find("seq/gnss.csv:2: 6 columns"),
            std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,46,6,400,0.5,0.5,1,9\n").find(":2: more than 7"),
            std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,46,6,nan,0.5,0.5,1\n").find(":2: not a finite number 'nan'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,91,6,400,0.5,0.5,1\n").find(":2: latitude"), std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,46,181,400,0.5,0.5,1\n").find(":2: longitude"), std::string::npos);
  EXPECT_NE(ErrorOf(kHeader + "0,46,6,400,0.5,0,1\n").find(":2: a sigma is not > 0"),
            std::string::npos);
  const std::string twice = kHeader + "1,46,6,400,0.5,0.5,1\n1,46,6,400,0.5,0.5,1\n";
  EXPECT_NE(ErrorOf(twice).find(":3: timestamp 1.000000 is not after the previous one (line 2)"),
            std::string::npos)
      << ErrorOf(twice);
  EXPECT_THROW(io::ReadGnssCsv("/nonexistent/gnss.csv"), io::IoError);
}

TEST(GnssCsv, GeodeticToEnuInvertsEnuToGeodetic) {
  const io::Georeference georef({46.5191, 6.5668, 400.0});
  for (const Eigen::Vector3d& enu : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(150.0, -320.5, 12.0),
                                     Eigen::Vector3d(-2500.0, 1800.0, -40.0)}) {
    const Eigen::Vector3d geo = georef.EnuToGeodetic(enu.x(), enu.y(), enu.z());
    EXPECT_LT((georef.GeodeticToEnu(geo.x(), geo.y(), geo.z()) - enu).norm(), 1e-6);
  }
  // 1 arc second of latitude is about 30.9 m north here.
  const Eigen::Vector3d north = georef.GeodeticToEnu(46.5191 + 1.0 / 3600.0, 6.5668, 400.0);
  EXPECT_NEAR(north.y(), 30.9, 0.1);
  EXPECT_NEAR(north.x(), 0.0, 1e-6);
}
