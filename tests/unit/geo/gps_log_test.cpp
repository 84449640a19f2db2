#include "geo/gps_log.h"

#include <gtest/gtest.h>

#include <sstream>

#include "base/error.h"

namespace mvtm {
namespace {

GpsLog Parse(const std::string& text) {
  std::istringstream in(text);
  return ReadGpsLog(in, "log");
}

std::string ErrorOf(const std::string& text) {
  try {
    Parse(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The example of the NMEA 0183 RMC sentence every reference quotes (checksum 6A): 12:35:19 UTC on
// 23 March 1994, 48°07.038' N 11°31.000' E. 1994-03-23 is day 8847 after 1970-01-01 (24 years of
// 365 days, 6 leap days 1972..1992, then 31 + 28 + 22 days), so 8847·86400 + 12·3600 + 35·60 + 19.
TEST(GpsLog, NmeaStandardExample) {
  const GpsLog log = Parse(
      "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"
      "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n");
  ASSERT_EQ(log.fixes.size(), 1u);
  EXPECT_EQ(log.format, "nmea");
  EXPECT_DOUBLE_EQ(log.fixes[0].time, 8847.0 * 86400 + 12 * 3600 + 35 * 60 + 19);
  EXPECT_DOUBLE_EQ(log.fixes[0].time, 764426119.0);
  EXPECT_NEAR(log.fixes[0].lat, 48 + 7.038 / 60, 1e-12);
  EXPECT_NEAR(log.fixes[0].lon, 11 + 31.0 / 60, 1e-12);
  EXPECT_TRUE(log.fixes[0].has_alt);
  EXPECT_DOUBLE_EQ(log.fixes[0].alt, 545.4);
  EXPECT_EQ(log.bad_checksums, 0u);
}

TEST(GpsLog, NmeaWrongChecksumsAreSkippedAndCounted) {
  const GpsLog log = Parse(
      "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6B\n"  // wrong
      "$GPRMC,123520,A,4807.038,S,01131.000,W,022.4,084.4,230394,003.1,W*XX\n"  // not hex
      "$GPRMC,123521,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W\n"     // missing
      "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\n");
  EXPECT_EQ(log.bad_checksums, 3u);
  ASSERT_EQ(log.fixes.size(), 1u);
  EXPECT_DOUBLE_EQ(log.fixes[0].time, 764426119.0);
}

TEST(GpsLog, NmeaWithoutAValidFixIsAnError) {
  EXPECT_NE(ErrorOf("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6B\n")
                .find("checksum"),
            std::string::npos);
  // GGA alone has no date.
  EXPECT_NE(ErrorOf("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\n")
                .find("no date"),
            std::string::npos);
}

TEST(GpsLog, IsoTimes) {
  double t;
  ASSERT_TRUE(ParseIsoTime("1970-01-01T00:00:00Z", t));
  EXPECT_EQ(t, 0);
  ASSERT_TRUE(ParseIsoTime("1994-03-23T12:35:19Z", t));
  EXPECT_EQ(t, 764426119.0);
  ASSERT_TRUE(ParseIsoTime("1994-03-23T14:35:19.25+02:00", t));  // the same instant, +¼ s
  EXPECT_EQ(t, 764426119.25);
  ASSERT_TRUE(ParseIsoTime("1994-03-23T07:05:19-0530", t));
  EXPECT_EQ(t, 764426119.0);
  ASSERT_TRUE(ParseIsoTime("2000-02-29T00:00:00Z", t));  // a leap day (divisible by 400)
  EXPECT_EQ(t, 951782400.0);
  EXPECT_EQ(FormatIsoTime(764426119.25), "1994-03-23T12:35:19.250Z");
  EXPECT_EQ(FormatIsoTime(951782400.0), "2000-02-29T00:00:00.000Z");
  EXPECT_EQ(FormatIsoTime(-1.0), "1969-12-31T23:59:59.000Z");
  EXPECT_FALSE(ParseIsoTime("1994-03-23", t));
  EXPECT_FALSE(ParseIsoTime("1994-13-23T12:35:19Z", t));
  EXPECT_FALSE(ParseIsoTime("1994-03-23T12:35:19Q", t));
}

TEST(GpsLog, GpxTrackPointsSortedWithElevation) {
  const GpsLog log = Parse(
      "<?xml version=\"1.0\"?>\n<gpx version=\"1.1\"><trk><trkseg>\n"
      "<trkpt lat=\"49.5\" lon=\"8.25\"><ele>110.5</ele><time>1994-03-23T12:35:20Z</time></trkpt>\n"
      "<trkpt lat=\"49.4\" lon=\"8.2\"><time>1994-03-23T12:35:19Z</time></trkpt>\n"
      "</trkseg></trk></gpx>\n");
  ASSERT_EQ(log.fixes.size(), 2u);
  EXPECT_EQ(log.format, "gpx");
  EXPECT_EQ(log.fixes[0].time, 764426119.0);
  EXPECT_DOUBLE_EQ(log.fixes[0].lat, 49.4);
  EXPECT_FALSE(log.fixes[0].has_alt);
  EXPECT_DOUBLE_EQ(log.fixes[1].alt, 110.5);
  EXPECT_TRUE(log.fixes[1].has_alt);
}

TEST(GpsLog, GpxWithoutTimesOrBrokenIsAnError) {
  EXPECT_NE(
      ErrorOf("<gpx><trk><trkseg><trkpt lat=\"1\" lon=\"2\"/></trkseg></trk></gpx>").find("<time>"),
      std::string::npos);
  EXPECT_NE(ErrorOf("<gpx><trk><trkseg><trkpt lat=\"1\"").find("well-formed"), std::string::npos);
  EXPECT_NE(ErrorOf("<kml></kml>").find("no <gpx>"), std::string::npos);
  EXPECT_NE(ErrorOf("hello").find("not a GPS log"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("empty"), std::string::npos);
}

}  // namespace
}  // namespace mvtm
