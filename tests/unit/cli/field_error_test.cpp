// A library names a bad value by its options struct's field (FieldError); the tool's main names
// the flag that set it, through the declared option table, and exits 2.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <sstream>

#include "base/error.h"
#include "cli/app.h"
#include "cli/options.h"

namespace mvtm {
namespace {

struct Opts {
  int neighbours = 4;
  int window = 7;
};

std::string RunAndCaptureError(const std::string& field, int& status) {
  Opts o;
  OptionTable t("demo");
  t.Integer("--neighbours", &o.neighbours, "Neighbours").Field("count");
  t.Integer("--window", &o.window, "Window");
  CLI::App app;
  ConfigureApp(app, "demo", "A demo");
  AddOptionTable(app, t);
  const char* argv[] = {"demo", "--neighbours", "20"};
  std::ostringstream err;
  std::streambuf* old = std::cerr.rdbuf(err.rdbuf());
  status = RunMain(app, "demo", 3, const_cast<char**>(argv),
                   [&]() -> int { throw FieldError(field, "must be 1..16"); });
  std::cerr.rdbuf(old);
  return err.str();
}

TEST(FieldError, MainNamesTheFlagThatSetTheField) {
  int status = 0;
  EXPECT_EQ(RunAndCaptureError("count", status), "demo: error: --neighbours: must be 1..16\n");
  EXPECT_EQ(status, 2);
  EXPECT_EQ(RunAndCaptureError("window", status), "demo: error: --window: must be 1..16\n");
  // A field no option sets is named as it is.
  EXPECT_EQ(RunAndCaptureError("radius", status), "demo: error: radius: must be 1..16\n");
}

}  // namespace
}  // namespace mvtm
