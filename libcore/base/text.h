// mvtm — line-oriented text input with FILE:LINE diagnostics.
//
// Every text reader in mvtm goes through LineReader so that any malformed input is reported as
// "FILE:LINE: what" and never crashes. Numbers are parsed with std::from_chars, which ignores the
// global locale (a comma-decimal locale cannot change how "1.5" reads). Non-finite values
// ("nan", "inf") are rejected unless a caller asks for them. Lines may end in CRLF, and a UTF-8
// byte-order mark at the start of a file is skipped.
#pragma once

#include <cstdint>
#include <fstream>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace mvtm {

class LineReader {
 public:
  // Opens `path`; throws Error("PATH: cannot open") when it cannot.
  explicit LineReader(const std::string& path);
  // Reads from an already open stream; `name` is used in messages.
  LineReader(std::istream& in, std::string name);

  // Next line with surrounding whitespace removed. Blank lines and, when skip_comments, lines
  // whose first non-blank character is '#' are skipped. Returns false at end of input.
  bool Next(std::string& line, bool skip_comments = true);
  // Next raw line (nothing skipped, CR stripped). Returns false at end of input.
  bool NextRaw(std::string& line);

  long line() const { return line_no_; }
  const std::string& name() const { return name_; }

  // Throws Error(name, line, what).
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  std::unique_ptr<std::ifstream> owned_;
  std::istream* in_ = nullptr;
  std::string name_;
  long line_no_ = 0;
};

// Splits on blanks (spaces and tabs).
std::vector<std::string_view> SplitBlank(std::string_view s);
// Splits on a single character, keeping empty fields.
std::vector<std::string_view> SplitChar(std::string_view s, char c);
std::string_view Trim(std::string_view s);

// Parsers that throw Error(reader.name(), reader.line(), "...") naming the field.
double ParseDouble(std::string_view token, const LineReader& at, const char* field,
                   bool allow_nonfinite = false);
int64_t ParseInt(std::string_view token, const LineReader& at, const char* field);
// Location-free variants for option values; throw UsageError naming `what`.
double ParseDoubleArg(std::string_view token, const std::string& what);
int64_t ParseIntArg(std::string_view token, const std::string& what);

// A header row naming columns (TSV logs: drive's controls, gazemap's gaze). Reads the first
// non-comment line of `r`: it must name columns, not be a row of numbers; no name twice; every
// `required` name present. Returns the column index of each of `required` then `optional`
// (-1 for an optional column absent) and the number of fields; other names go to `ignored`.
// `expected` ("time steer speed") is shown in messages.
struct ColumnHeader {
  size_t fields = 0;
  std::vector<long> index;
  std::vector<std::string> ignored;
};
ColumnHeader ReadColumnHeader(LineReader& r, const std::vector<std::string>& required,
                              const std::vector<std::string>& optional,
                              const std::string& expected);

// For logs whose rows must be in strictly increasing time: fails at r's current line with
// "time T repeats line L" or "time T is before line L's P: samples must be in time order"
// unless t > prev_time (the time of line prev_line).
void CheckTimeAfter(const LineReader& r, double t, double prev_time, long prev_line);

// "%.17g" — round-trips every double exactly, locale-independent.
std::string FormatDouble(double v);
// The shortest text that reads back as v ("0.1", where FormatDouble gives
// "0.10000000000000001"): for messages.
std::string FormatShort(double v);

}  // namespace mvtm
