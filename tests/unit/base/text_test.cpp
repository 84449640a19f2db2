// LineReader and number parsing: locale independence, FILE:LINE messages, non-finite values.
#include "base/text.h"

#include <gtest/gtest.h>

#include <clocale>
#include <locale>
#include <sstream>

#include "../io/comma_locale.h"
#include "base/error.h"

namespace mvtm {
namespace {

TEST(Text, ParsesWithClassicRulesUnderCommaLocale) {
  // A comma-decimal global locale must not change how "1.5" reads or how doubles print.
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");
  std::istringstream in("# comment\n\n  1.5 2e3\t-0.25  \n");
  LineReader r(in, "x.txt");
  std::string line;
  ASSERT_TRUE(r.Next(line));
  EXPECT_EQ(r.line(), 3);
  auto tok = SplitBlank(line);
  ASSERT_EQ(tok.size(), 3u);
  EXPECT_EQ(ParseDouble(tok[0], r, "a"), 1.5);
  EXPECT_EQ(ParseDouble(tok[1], r, "b"), 2000.0);
  EXPECT_EQ(ParseDouble(tok[2], r, "c"), -0.25);
  EXPECT_EQ(FormatDouble(0.1), "0.10000000000000001");  // %.17g, with a point
  EXPECT_FALSE(r.Next(line));
}

TEST(Text, ErrorsNameFileLineAndField) {
  std::istringstream in("1 2\n3 nan\n4 1,5\n");
  LineReader r(in, "poses.txt");
  std::string line;
  r.Next(line);
  r.Next(line);
  try {
    ParseDouble(SplitBlank(line)[1], r, "ty");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "poses.txt:2: ty: 'nan' is not finite");
  }
  r.Next(line);
  try {
    ParseDouble(SplitBlank(line)[1], r, "tz");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "poses.txt:3: tz: '1,5' is not a number");
  }
  EXPECT_THROW(ParseInt("3.5", r, "id"), Error);
  EXPECT_THROW(ParseInt("", r, "id"), Error);
}

TEST(Text, RoundTripsEveryDouble) {
  // %.17g must read back bit for bit; a few awkward values.
  std::istringstream dummy("");
  LineReader r(dummy, "-");
  for (double v : {0.1, 1.0 / 3.0, 5.4210108624275246e-20, 4.5e6 + 1e-9, -0.0, 1e308, 4.9e-324}) {
    EXPECT_EQ(ParseDouble(FormatDouble(v), r, "v"), v) << FormatDouble(v);
  }
}

TEST(Text, SplitKeepsEmptyFieldsOnChar) {
  auto f = SplitChar("a\t\tb", '\t');
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[1], "");
  EXPECT_EQ(Trim("  x \r\n"), "x");
}

}  // namespace
}  // namespace mvtm
