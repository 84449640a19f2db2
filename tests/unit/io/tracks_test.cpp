// tracks.tsv: exact round trips (also under a comma-decimal locale), the bytes segtrack(1)
// documents, and FILE:LINE errors for malformed rows.
#include "io/tracks.h"

#include <gtest/gtest.h>

#include <sstream>

#include "base/error.h"
#include "comma_locale.h"
#include "test_util.h"

namespace mvtm {
namespace {

TracksTsvRow Row(int frame, const std::string& name, int track, RowState state, int x, int y, int w,
                 int h, double cx, double cy, int area, double scx, double scy, double sw,
                 double sh) {
  TracksTsvRow r;
  r.name = name;
  r.row.frame = frame, r.row.track = track, r.row.state = state;
  r.row.x = x, r.row.y = y, r.row.w = w, r.row.h = h, r.row.cx = cx, r.row.cy = cy,
  r.row.area = area;
  r.row.scx = scx, r.row.scy = scy, r.row.sw = sw, r.row.sh = sh;
  return r;
}

// Values with at most three decimals, so the round trip is exact; large ones would be grouped
// ("12.345") by a comma locale if the writer let the stream format them.
std::vector<TracksTsvRow> SomeRows() {
  return {Row(0, "0001.png", 1, RowState::kDetected, 10, 5, 4, 3, 11.5, 6, 12, 11.5, 6, 4, 3),
          Row(0, "0001.png", 2, RowState::kRejected, 1234, 2, 1, 1, 1234, 2, 1, 1234, 2, 1, 1),
          Row(1, "0002.png", 1, RowState::kInterpolated, -3, 7, 0, 0, -1.25, 7.125, 0, -1.25, 7.125,
              4.001, 2.999),
          Row(3, "sub dir/0004.png", 1, RowState::kDetected, 20000, 15000, 1500, 1200, 20749.5,
              15599.5, 1800000, 20749.333, 15599.667, 1500.5, 1200.25)};
}

void ExpectSame(const std::vector<TracksTsvRow>& a, const std::vector<TracksTsvRow>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(i);
    const TrackRow &p = a[i].row, &q = b[i].row;
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(p.frame, q.frame);
    EXPECT_EQ(p.track, q.track);
    EXPECT_EQ(p.state, q.state);
    EXPECT_EQ(std::make_tuple(p.x, p.y, p.w, p.h, p.area),
              std::make_tuple(q.x, q.y, q.w, q.h, q.area));
    EXPECT_EQ(std::make_tuple(p.cx, p.cy, p.scx, p.scy, p.sw, p.sh),
              std::make_tuple(q.cx, q.cy, q.scx, q.scy, q.sw, q.sh));
  }
}

TEST(TracksTsv, WritesTheDocumentedColumns) {
  std::ostringstream out;
  WriteTracksTsv(out, {SomeRows()[0], SomeRows()[2]});
  EXPECT_EQ(
      out.str(),
      "frame\tname\ttrack\tstate\tx\ty\tw\th\tcx\tcy\tarea\tscx\tscy\tsw\tsh\n"
      "0\t0001.png\t1\tdetected\t10\t5\t4\t3\t11.500\t6.000\t12\t11.500\t6.000\t4.000\t3.000\n"
      "1\t0002.png\t1\tinterpolated\t-3\t7\t0\t0\t-1.250\t7.125\t0\t-1.250\t7.125\t4.001\t2.999\n");
  // Three decimals, rounded like printf's "%.3f": exactly (0.0005 is a little above a half in
  // binary) and ties to even (2.0625).
  std::ostringstream r;
  WriteTracksTsv(r, {Row(0, "a", 1, RowState::kDetected, 0, 0, 1, 1, 0.0005, 2.0625, 1, 1e-9,
                         -0.0004, 2.5, 1)});
  EXPECT_NE(r.str().find("\t0.001\t2.062\t1\t0.000\t-0.000\t2.500\t1.000\n"), std::string::npos)
      << r.str();
}

TEST(TracksTsv, RoundTripIsExactUnderCommaLocale) {
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");
  auto d = test::FreshDir("tracks");
  const auto rows = SomeRows();
  WriteTracksTsv((d / "tracks.tsv").string(), rows);
  const auto back = ReadTracksTsv((d / "tracks.tsv").string());
  ExpectSame(rows, back);
  // The stream versions give the same rows and the same bytes.
  std::istringstream in(test::ReadFile(d / "tracks.tsv"));
  ExpectSame(back, ReadTracksTsv(in, "tracks.tsv"));
  std::ostringstream again;
  WriteTracksTsv(again, back);
  EXPECT_EQ(again.str(), test::ReadFile(d / "tracks.tsv"));
  EXPECT_NE(again.str().find("\t1234\t2\t1\t1\t1234.000\t"), std::string::npos) << again.str();
  // No temporary file is left behind.
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(d)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  // A header alone is an empty table.
  std::istringstream header(
      "frame\tname\ttrack\tstate\tx\ty\tw\th\tcx\tcy\tarea\tscx\tscy\tsw\tsh\r\n");
  EXPECT_TRUE(ReadTracksTsv(header, "h").empty());
}

TEST(TracksTsv, MalformedInputNamesFileAndLine) {
  const std::string header =
      "frame\tname\ttrack\tstate\tx\ty\tw\th\tcx\tcy\tarea\tscx\tscy\tsw\tsh\n";
  const std::string good =
      "0\ta.png\t1\tdetected\t1\t2\t3\t4\t1.500\t2.500\t12\t1.500\t2.500\t3.000\t4.000\n";
  struct C {
    std::string text, msg;
  };
  const std::vector<C> cases = {
      {"", "t.tsv: no header line"},
      {"frame name track\n",
       "t.tsv:1: not a tracks.tsv header: expected the tab-separated columns frame name track "
       "state x y w h cx cy area scx scy sw sh"},
      {header + "0\ta.png\t1\tdetected\t1\t2\t3\t4\t1.5\n",
       "t.tsv:2: row needs 15 tab-separated fields, found 9"},
      {header + good + "1\ta.png\t1\tlost\t1\t2\t3\t4\t1\t2\t12\t1\t2\t3\t4\n",
       "t.tsv:3: state: 'lost' is not detected, interpolated or rejected"},
      {header + "-1\ta.png\t1\tdetected\t1\t2\t3\t4\t1\t2\t12\t1\t2\t3\t4\n",
       "t.tsv:2: frame: -1 is out of range 0..2147483647"},
      {header + "0\ta.png\t0\tdetected\t1\t2\t3\t4\t1\t2\t12\t1\t2\t3\t4\n",
       "t.tsv:2: track: 0 is out of range 1..2147483647"},
      {header + "0\t\t1\tdetected\t1\t2\t3\t4\t1\t2\t12\t1\t2\t3\t4\n", "t.tsv:2: name is empty"},
      {header + "0\ta.png\t1\tdetected\t1\t2\t3\t4\t1,5\t2\t12\t1\t2\t3\t4\n",
       "t.tsv:2: cx: '1,5' is not a number"},
      {header + "0\ta.png\t1\tdetected\t1\t2\t3\t4\t1\t2\t12\tnan\t2\t3\t4\n",
       "t.tsv:2: scx: 'nan' is not finite"},
      {header + "0\ta.png\t1\tdetected\t1\t2\t3.5\t4\t1\t2\t12\t1\t2\t3\t4\n",
       "t.tsv:2: w: '3.5' is not an integer"},
      {header + good + good,
       "t.tsv:3: rows must be sorted by frame, then track: frame 0 track 1 follows frame 0 track "
       "1"},
  };
  auto d = test::FreshDir("tracks-bad");
  for (const auto& c : cases) {
    test::WriteFile(d / "t.tsv", c.text);
    try {
      ReadTracksTsv((d / "t.tsv").string());
      ADD_FAILURE() << c.msg;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), (d / c.msg).string());
    }
    std::istringstream in(c.text);
    try {
      ReadTracksTsv(in, "-");
      ADD_FAILURE() << c.msg;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), "-" + c.msg.substr(5));
    }
  }
  EXPECT_THROW(ReadTracksTsv((d / "missing.tsv").string()), Error);
}

}  // namespace
}  // namespace mvtm
