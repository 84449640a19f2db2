// mvtm — the option groups every tool shares, put into a CLI11 table (one definition, so the
// same option reads and validates alike in every program and --help says the same thing).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli/work.h"
#include "run/option_table.h"

namespace mvtm {

// Puts a declared option table into a CLI11 app: every option, its type, default and choices,
// its exclusions; and the hidden flag --options-json, which prints OptionTable::Describe() (the
// option-walking test reads it) and exits 0. `table` must outlive the parse.
void AddOptionTable(CLI::App& app, OptionTable& table);

// The table AddOptionTable() put into this process's command line (nullptr before): RunMain names
// a library's FieldError by its flag through it.
const OptionTable* CommandLineTable();

// --frames A:B and --shard I/N (mutually exclusive), --force, -q/--quiet.
//   items:      what is selected, plural ("poses", "images", "label frames")
//   order:      the documented order of the items ("in pose order", "by name order")
//   force_help: what --force redoes for this tool
void AddWorkOptions(CLI::App& app, WorkOptions& work, const std::string& items,
                    const std::string& order, const std::string& force_help);

// -q/--quiet alone, for tools without a work list.
void AddQuietOption(CLI::App& app, bool& quiet);

// A choice option whose allowed values come from a name table (an enum's names, or a tool's
// documented list): --help lists them, CLI11 rejects anything else with the same list, and the
// tool's Check() uses CheckChoice() on the same table.
CLI::Option* AddChoiceOption(CLI::App& app, const std::string& name, std::string& value,
                             const std::vector<std::string>& choices, const std::string& help);

}  // namespace mvtm
