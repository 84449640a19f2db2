// mvtm — errors.
//
// Library code throws; only a tool's main() catches (libcore never prints or exits).
//   Error       bad data or a failed operation: exit status 1.
//   UsageError  a bad command line or option value: exit status 2.
// A message that concerns a place in a file reads "FILE:LINE: what" (LINE omitted when 0),
// so the tool prints "tool: error: FILE:LINE: what" on one line.
#pragma once

#include <stdexcept>
#include <string>

namespace mvtm {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what);
  Error(const std::string& file, long line, const std::string& what);
  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  std::string file_;
  long line_ = 0;
};

class UsageError : public Error {
 public:
  using Error::Error;
};

// A bad value of an option field of a library's options struct, tagged by the field's name
// ("window", "max_jump"), never by a command-line flag: libcore does not know the command line.
// what() reads "FIELD: problem"; a tool's main() names the flag instead ("--window: problem")
// through its option table (cli/app.h).
class FieldError : public UsageError {
 public:
  FieldError(std::string field, const std::string& problem)
      : UsageError(field + ": " + problem), field_(std::move(field)), problem_(problem) {}
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string field_, problem_;
};

// Formats "FILE:LINE: what" (or "FILE: what" when line == 0, "what" when file is empty).
std::string Located(const std::string& file, long line, const std::string& what);

}  // namespace mvtm
