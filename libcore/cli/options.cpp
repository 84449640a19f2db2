#include "cli/options.h"

namespace mvtm {

void AddWorkOptions(CLI::App& app, WorkOptions& work, const std::string& items,
                    const std::string& order, const std::string& force_help) {
  auto* fr =
      app.add_option("--frames", work.frames, "Only " + items + " A:B (half-open, " + order + ")");
  auto* sh = app.add_option("--shard", work.shard, "Only " + items + " i with i % N == I (I/N)");
  fr->excludes(sh);
  app.add_flag("--force", work.force, force_help);
  AddQuietOption(app, work.quiet);
}

void AddQuietOption(CLI::App& app, bool& quiet) {
  app.add_flag("-q,--quiet", quiet, "No progress bar or summary");
}

CLI::Option* AddChoiceOption(CLI::App& app, const std::string& name, std::string& value,
                             const std::vector<std::string>& choices, const std::string& help) {
  return app.add_option(name, value, help)->check(CLI::IsMember(choices))->capture_default_str();
}

}  // namespace mvtm
