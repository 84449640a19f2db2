// mvtm — a tool's declared option table (run/option_table.h) put into CLI11, so every option
// reads and validates alike in every program and --help says what the table says.
#pragma once

#include <string>
#include <vector>

#include "cli/work.h"
#include "run/option_table.h"

namespace CLI {
class App;  // <CLI/CLI.hpp>: included by the code that makes an app
}

namespace mvtm {

// Puts a declared option table into a CLI11 app: every option, its type, default and choices,
// its exclusions; and the hidden flag --options-json, which prints OptionTable::Describe() (the
// option-walking test reads it) and exits 0. `table` must outlive the parse.
void AddOptionTable(CLI::App& app, OptionTable& table);

// The table AddOptionTable() put into this process's command line (nullptr before): RunMain names
// a library's FieldError by its flag through it.
const OptionTable* CommandLineTable();

}  // namespace mvtm
