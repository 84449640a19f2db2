// partners.tsv: exact text written (the format of man/pickview.1), round trips under a
// comma-decimal locale, the path writer's atomicity, rank order per query, FILE:LINE errors.
#include "io/partners.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <iterator>
#include <sstream>

#include "base/error.h"
#include "comma_locale.h"
#include "test_util.h"

namespace mvtm {
namespace {

const char* kHeader = "query\trank\timage\tdistance\theading_deg\n";

std::vector<PartnerRow> SomeRows() {
  return {{"A_0000.png", 1, "B_0003.png", 1234.5, 0.25},
          {"A_0000.png", 2, "cam 1/B 0004.png", 2.0, 44.125},
          {"A_0001.png", 1, "B_0000.png", 0.0000004, 12345678.5}};
}

TEST(Partners, WritesTheDocumentedTextUnderCommaLocale) {
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");
  std::ostringstream s;  // takes the comma locale: the writer must not
  WritePartners(s, SomeRows());
  EXPECT_EQ(s.str(), std::string(kHeader) +
                         "A_0000.png\t1\tB_0003.png\t1234.500000\t0.250000\n"
                         "A_0000.png\t2\tcam 1/B 0004.png\t2.000000\t44.125000\n"
                         "A_0001.png\t1\tB_0000.png\t0.000000\t12345678.500000\n");
}

TEST(Partners, RoundTripUnderCommaLocaleStreamAndPath) {
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");
  auto d = test::FreshDir("partners-rt");
  std::vector<PartnerRow> rows = SomeRows();
  rows[2].distance = 0.000001;  // representable at 6 decimals, so the round trip is exact
  const std::string path = (d / "partners.tsv").string();
  WritePartners(path, rows);
  std::ostringstream s;
  WritePartners(s, rows);
  EXPECT_EQ(test::ReadFile(path), s.str());
  std::filesystem::directory_iterator files(d);
  EXPECT_EQ(std::distance(begin(files), end(files)), 1) << "no temporary file is left beside it";
  std::istringstream in(s.str());
  for (const std::vector<PartnerRow>& back : {ReadPartners(path), ReadPartners(in, "-")}) {
    ASSERT_EQ(back.size(), rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(back[i].query, rows[i].query);
      EXPECT_EQ(back[i].rank, rows[i].rank);
      EXPECT_EQ(back[i].image, rows[i].image);
      EXPECT_EQ(back[i].distance, rows[i].distance);
      EXPECT_EQ(back[i].heading_deg, rows[i].heading_deg);
    }
  }
}

TEST(Partners, ReadsCommentsBlankLinesAndCrlf) {
  std::istringstream in(
      "# pickview\r\nquery rank image distance heading_deg\r\n\r\n"
      "q\t3\tc\t1.5\t2\r\n");
  auto rows = ReadPartners(in, "x.tsv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].query, "q");
  EXPECT_EQ(rows[0].rank, 3);
  EXPECT_EQ(rows[0].image, "c");
  EXPECT_EQ(rows[0].distance, 1.5);
  EXPECT_EQ(rows[0].heading_deg, 2.0);
}

TEST(Partners, ByQueryInRankOrderStable) {
  std::vector<PartnerRow> rows = {
      {"b", 2, "x2", 0, 0}, {"a", 1, "y", 0, 0}, {"b", 1, "x1", 0, 0}, {"b", 2, "x3", 0, 0}};
  auto by = PartnersByQuery(rows);
  ASSERT_EQ(by.size(), 2u);
  EXPECT_EQ(by["a"], std::vector<std::string>({"y"}));
  EXPECT_EQ(by["b"], std::vector<std::string>({"x1", "x2", "x3"}));
}

TEST(Partners, ErrorsNameFileAndLine) {
  auto d = test::FreshDir("partners-bad");
  const std::string h = kHeader;
  struct C {
    std::string text, msg;
  };
  std::vector<C> cases = {
      {"", "p.tsv: empty file: expected the header 'query rank image distance heading_deg'"},
      {"# only a comment\n",
       "p.tsv:1: empty file: expected the header 'query rank image distance heading_deg'"},
      {"query\trank\tname\tdistance\theading_deg\n",
       "p.tsv:1: expected the header 'query rank image distance heading_deg' (pickview "
       "--partners)"},
      {"\n" + h + "a\t1\tb\t0.5\n", "p.tsv:3: expected 5 tab-separated fields, found 4"},
      {h + "a\t1\tb\t0.5\t1\t7\n", "p.tsv:2: expected 5 tab-separated fields, found 6"},
      {h + "a\t1\tb\t0.5\t1\n# c\na\tx\tb\t0.5\t1\n", "p.tsv:4: rank: 'x' is not an integer"},
      {h + "a\t0\tb\t0.5\t1\n", "p.tsv:2: rank must be >= 1"},
      {h + "a\t1\tb\tnan\t1\n", "p.tsv:2: distance: 'nan' is not finite"},
      {h + "a\t1\tb\t0,5\t1\n", "p.tsv:2: distance: '0,5' is not a number"},
      {h + "a\t1\tb\t0.5\t\n", "p.tsv:2: expected 5 tab-separated fields, found 4"},
      {h + "a\t1\tb\t0.5\tx\n", "p.tsv:2: heading_deg: 'x' is not a number"},
  };
  for (const C& c : cases) {
    test::WriteFile(d / "p.tsv", c.text);
    try {
      ReadPartners((d / "p.tsv").string());
      ADD_FAILURE() << "no error for: " << c.text;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), (d / c.msg).string()) << c.text;
    }
    std::istringstream in(c.text);
    try {
      ReadPartners(in, "p.tsv");
      ADD_FAILURE() << "no error for: " << c.text;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), c.msg) << c.text;
    }
  }
  try {
    ReadPartners((d / "none.tsv").string());
    ADD_FAILURE() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (d / "none.tsv: cannot open").string());
  }
}

}  // namespace
}  // namespace mvtm
