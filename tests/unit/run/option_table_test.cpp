// The declared option table: values parsed strictly, ranges checked with the flag named, the
// provenance and staleness JSON exactly the declared options.
#include "run/option_table.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

enum class Colour { kRed, kGreen };

struct Opts {
  std::string ws;
  double bias = 0.005;
  int k = 4;
  bool quiet = false;
  Colour colour = Colour::kRed;
  std::string size;
};

OptionTable Declare(Opts& o) {
  OptionTable t("demo");
  t.Positional("WS", &o.ws, "Workspace").Dir();
  t.Real("--bias", &o.bias, "Bias").Range(0, 1, false, true);
  t.Integer("--projectors", &o.k, "K").Range(1, 16);
  t.Flag("-q,--quiet", &o.quiet, "Quiet").Cosmetic();
  t.Choice("--colour", &o.colour, {{Colour::kRed, "red"}, {Colour::kGreen, "green"}}, "Colour");
  t.Text("--size", &o.size, "WxH").Check([&o] {
    if (o.size == "bad") throw UsageError("--size: 'bad' is not WxH");
  });
  return t;
}

const OptionSpec& Spec(const OptionTable& t, const std::string& flag) {
  const OptionSpec* s = t.Find(flag);
  EXPECT_NE(s, nullptr) << flag;
  return *s;
}

TEST(OptionTable, KeysAreLongNamesWithUnderscoresAndDefaultsAreTheDeclaredValues) {
  Opts o;
  OptionTable t = Declare(o);
  EXPECT_EQ(Spec(t, "--quiet").key, "quiet");
  EXPECT_EQ(Spec(t, "WS").key, "ws");
  EXPECT_EQ(Spec(t, "--bias").default_text, "0.005");
  EXPECT_EQ(Spec(t, "--colour").type, "red|green");
  // Every declared option is in the provenance; the staleness key leaves out the cosmetic ones
  // and the paths (their files are inputs).
  EXPECT_EQ(t.Json().size(), 6u);
  const nlohmann::json key = t.OutputJson();
  EXPECT_EQ(key.size(), 4u);
  EXPECT_FALSE(key.contains("quiet"));
  EXPECT_FALSE(key.contains("ws"));
  EXPECT_EQ(key["colour"], "red");
}

TEST(OptionTable, ValuesParseStrictlyIntoTheirFields) {
  Opts o;
  OptionTable t = Declare(o);
  Spec(t, "--bias").set("0.25");
  Spec(t, "--projectors").set("7");
  Spec(t, "--colour").set("green");
  Spec(t, "--quiet").set("1");
  EXPECT_EQ(o.bias, 0.25);
  EXPECT_EQ(o.k, 7);
  EXPECT_EQ(o.colour, Colour::kGreen);
  EXPECT_TRUE(o.quiet);
  EXPECT_THROW(Spec(t, "--bias").set("0,25"), UsageError);  // no locale decimal comma
  EXPECT_THROW(Spec(t, "--projectors").set("7.5"), UsageError);
  EXPECT_THROW(Spec(t, "--projectors").set("99999999999"), UsageError);  // beyond int
  try {
    Spec(t, "--colour").set("blue");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--colour: 'blue' is not one of red, green");
  }
}

TEST(OptionTable, CheckNamesTheFlagAndItsRange) {
  Opts o;
  o.ws = "w";
  OptionTable t = Declare(o);
  EXPECT_NO_THROW(t.Check());
  o.bias = 1;  // the upper bound is open
  try {
    t.Check();
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--bias: must be in [0, 1)");
  }
  o.bias = 0;
  o.k = 0;
  EXPECT_THROW(t.Check(), UsageError);
  o.k = 16;
  o.size = "bad";
  EXPECT_THROW(t.Check(), UsageError);
  o.size.clear();
  o.ws.clear();
  EXPECT_THROW(t.Check(), UsageError);  // a required positional
}

TEST(OptionTable, DescribeOffersAValidOtherValueForEveryOutputOption) {
  Opts o;
  OptionTable t = Declare(o);
  const nlohmann::json d = t.Describe();
  for (const auto& opt : d["options"]) {
    if (!opt["changes_output"].get<bool>() || opt["flag"] == "--size") continue;
    const std::string alt = opt["alternative"];
    ASSERT_FALSE(alt.empty()) << opt["flag"];
    EXPECT_NE(alt, opt["default"].get<std::string>()) << opt["flag"];
    Opts copy;
    copy.ws = "w";
    OptionTable c = Declare(copy);
    c.Find(opt["flag"])->set(alt);
    EXPECT_NO_THROW(c.Check()) << opt["flag"] << " " << alt;
  }
}

}  // namespace
}  // namespace mvtm
