// A comma-decimal global C++ locale for round-trip tests, built from a numpunct facet so that it
// exists on every machine (Debian's minimal images have no de_DE locale installed).
#pragma once
#include <locale>
#include <sstream>
#include <string>

namespace mvtm::test {

struct CommaDecimal : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
  char do_thousands_sep() const override { return '.'; }
  std::string do_grouping() const override { return "\3"; }
};

// Installs the comma locale as the global C++ locale for its lifetime.
class ScopedCommaLocale {
 public:
  ScopedCommaLocale()
      : previous_(std::locale::global(std::locale(std::locale::classic(), new CommaDecimal))) {}
  ~ScopedCommaLocale() { std::locale::global(previous_); }
  // A stream that was not told otherwise now writes 1234.5 as "1.234,5".
  static std::string Probe() {
    std::ostringstream os;
    os << 1234.5;
    return os.str();
  }

 private:
  std::locale previous_;
};

}  // namespace mvtm::test
