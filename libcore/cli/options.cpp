#include "cli/options.h"

#include <CLI/CLI.hpp>
#include <iostream>

namespace mvtm {

namespace {
const OptionTable* g_table = nullptr;  // the table of this process's command line
}  // namespace

const OptionTable* CommandLineTable() { return g_table; }

void AddOptionTable(CLI::App& app, OptionTable& table) {
  g_table = &table;
  for (const OptionSpec& s : table.options()) {
    if (s.hidden) continue;
    if (s.is_flag) {
      // A flag takes no value: `--no-flow=0` (any value but CLI11's "true") is a usage error,
      // not a silent "on".
      app.add_flag_function(
             s.names, [set = s.set](int64_t n) { set(n > 0 ? "1" : "0"); }, s.help)
          ->disable_flag_override();
      continue;
    }
    CLI::Option* o = nullptr;
    if (s.is_list)
      o = app.add_option_function<std::vector<std::string>>(
          s.names, [set = s.set_list](const std::vector<std::string>& v) { set(v); }, s.help);
    else
      o = app.add_option_function<std::string>(
          s.names, [set = s.set](const std::string& v) { set(v); }, s.help);
    o->type_name(s.type);
    if (!s.positional && !s.default_text.empty()) o->default_str(s.default_text);
    if (!s.choices.empty()) o->check(CLI::IsMember(s.choices));
    if (s.required) o->required();
  }
  for (const OptionSpec& s : table.options())
    for (const std::string& other : s.excludes) {
      CLI::Option* a = app.get_option_no_throw(s.flag);
      CLI::Option* b = app.get_option_no_throw(other);
      if (a && b) a->excludes(b);
    }
  app.add_flag_callback("--options-json",
                        [&table] {
                          std::cout << table.Describe().dump(1) << "\n";
                          throw CLI::Success();
                        })
      ->group("");
}

}  // namespace mvtm
