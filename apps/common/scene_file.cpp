// Scene files: --config FILE on every subcommand, the section filter, scene.toml (scene_file.hpp).
#include "scene_file.hpp"

#include <algorithm>
#include <filesystem>
#include <istream>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

namespace netdem::app {
namespace {

/// The options a scene holds: configurable, shown in --help, and not where the run is written.
bool scene_option(const CLI::Option& op) {
  static const std::set<std::string> outside = {"out", "overwrite", "config"};
  return op.get_configurable() && !op.get_group().empty() && outside.count(op.get_single_name()) == 0U;
}

/// The option of `app` a key names (a long option without "--", or a positional's name), or nullptr.
const CLI::Option* key_option(const CLI::App& app, const std::string& key) {
  for (const CLI::Option* op : app.get_options())
    if (scene_option(*op) && op->get_single_name() == key) return op;
  return nullptr;
}

/// CLI11's TOML reader (ConfigTOML), which then keeps the items of the subcommand that runs:
/// its section only, the other sections of the tool skipped, anything else refused (one line).
class SceneConfig : public CLI::ConfigTOML {
 public:
  SceneConfig(const CLI::App* app, std::string tool, std::string standalone, std::vector<std::string> sections)
      : app_(app), tool_(std::move(tool)), standalone_(std::move(standalone)), sections_(std::move(sections)) {}

  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    const CLI::App* sub = app_;
    std::string section = standalone_;
    if (section.empty()) {
      const auto parsed = app_->get_subcommands();
      if (parsed.empty()) return {};  // no subcommand: the parse refuses the command line
      sub = parsed.front();
      section = sub->get_name();
    }
    std::vector<CLI::ConfigItem> kept;
    for (CLI::ConfigItem item : CLI::ConfigTOML::from_config(input)) {
      const bool marker = item.name == "++" || item.name == "--";
      if (item.parents.empty()) {
        if (marker) continue;
        throw error(fmt::format("'{}' is outside a section: put it under [{}]", item.name, section));
      }
      if (item.parents.size() > 1) throw error(fmt::format("section [{}] is nested: a scene file is flat", item.fullname()));
      const std::string& s = item.parents.front();
      if (s != section) {
        if (std::find(sections_.begin(), sections_.end(), s) != sections_.end()) continue;  // another subcommand's
        throw error(fmt::format("[{}] is not a subcommand of {}", s, tool_));
      }
      if (!marker && key_option(*sub, item.name) == nullptr)
        throw error(fmt::format("[{}] {}: {} {} has no option --{} in a scene file", section, item.name, tool_,
                                section, item.name));
      if (!standalone_.empty()) {
        if (marker) continue;
        item.parents.clear();
      }
      kept.push_back(std::move(item));
    }
    return kept;
  }

 private:
  CLI::ConfigError error(const std::string& what) const {
    std::string file;
    if (const CLI::Option* c = app_->get_config_ptr(); c != nullptr && !c->results().empty()) file = c->results().back();
    return CLI::ConfigError(fmt::format("scene file '{}': {}", file.substr(0, 200), what));
  }

  const CLI::App* app_;
  std::string tool_, standalone_;
  std::vector<std::string> sections_;
};

constexpr const char* kConfigHelp =
    "read the options from this scene file (TOML, a section per subcommand, e.g. [compact] friction = 0.1; "
    "the command line overrides it; every run writes its own as scene.toml: README.md 'Scene files')";

/// The check of --config: a regular file (CLI11's ExistingFile takes a FIFO or a device, whose
/// reading may never end).
CLI::Validator existing_file() {
  return CLI::Validator(
      [](std::string& path) {
        std::error_code ec;
        const std::string shown = "'" + path.substr(0, 200) + "'";
        if (!std::filesystem::exists(path, ec)) return "no such file: " + shown;
        if (!std::filesystem::is_regular_file(path, ec)) return shown + " is not a regular file";
        return std::string();
      },
      "");
}

/// `value` as a TOML string the CLI11 reader gives back unchanged, or "" if it cannot.
std::string quoted(const std::string& value) {
  if (value.find_first_of("#\n\r") != std::string::npos) return "";
  if (value.find('"') == std::string::npos) return "\"" + value + "\"";
  if (value.find('\'') == std::string::npos) return "'" + value + "'";
  return "";
}

}  // namespace

void add_scene_config(CLI::App& app, const std::string& tool, const std::string& standalone_section,
                      const std::vector<std::string>& sections) {
  CLI::Option* config = app.set_config("--config", "", kConfigHelp);
  config->type_name("FILE")->check(existing_file());
  app.config_formatter(std::make_shared<SceneConfig>(&app, tool, standalone_section, sections));
  if (!standalone_section.empty()) return;
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (sub->get_options().size() <= 1) continue;  // a subcommand dispatched elsewhere (netsolve yield, ...)
    sub->add_option("--config", [config](const CLI::results_t& r) {
          config->add_result(r.back());
          return true;
        }, kConfigHelp)
        ->type_name("FILE")
        ->check(existing_file())
        ->configurable(false)
        ->trigger_on_parse();
  }
}

std::string scene_toml(const CLI::App& sub, const std::string& tool, const std::string& section) {
  std::string given, defaults;
  for (const CLI::Option* op : sub.get_options()) {
    if (!scene_option(*op)) continue;
    const std::string key = op->get_single_name();
    if (op->count() == 0) {
      const std::string d = op->get_expected_min() == 0 ? std::string("false") : op->get_default_str();
      const std::string q = quoted(d);
      defaults += d.empty() ? fmt::format("# {}: not given\n", key) : fmt::format("# {} = {}\n", key, q.empty() ? d : q);
      continue;
    }
    std::vector<std::string> values;
    bool ok = true;
    for (const std::string& r : op->results()) {
      values.push_back(quoted(r));
      ok = ok && !values.back().empty();
    }
    if (!ok) {
      given += fmt::format("# {}: its value holds '#' or a line break, which a scene file cannot hold\n", key);
    } else if (values.size() == 1 && !(op->get_items_expected_max() > 1 || op->get_delimiter() != '\0')) {
      given += fmt::format("{} = {}\n", key, values[0]);
    } else {
      given += fmt::format("{} = [{}]\n", key, fmt::join(values, ", "));
    }
  }
  return fmt::format("# {0} {1}: the options this run was given; `{0} {1} --config scene.toml --out DIR` reruns it\n"
                     "# (the command line overrides the file). A commented line is an option left at its default.\n"
                     "[{1}]\n{2}{3}",
                     tool, section, given, defaults);
}

}  // namespace netdem::app
