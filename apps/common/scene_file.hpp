#pragma once
// Scene files (README.md "Scene files", issue 33): every subcommand of netsolve and demsolve reads
// its options from a flat TOML file, `--config scene.toml`, with a section per subcommand
//
//   [compact]
//   friction = 0.1
//   to-density = "0.8"
//
// whose keys are the long options without "--"; the command line overrides the file. A file may
// hold the sections of several subcommands of its tool: a run reads its own and skips the others.
// A key outside a section, an unknown section or key, or a bad value is refused like a bad command
// line (one line, exit 2), as is a missing file or one that is not a regular file. Every run writes the options it was given, with
// every other option's default as a comment, to scene.toml in its run folder (open_run_dir), so that
// `--config RUN/scene.toml --out OTHER` reruns it. --out, --overwrite and --config are not part of
// a scene. Values are written as given (relative paths stay relative to the working folder).
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace netdem::app {

/// Adds --config FILE to `app`. With `standalone_section` empty, `app` is a tool's main app whose
/// subcommands are the sections (each subcommand of `app` gets its own --config, call after adding
/// them); otherwise `app` is the one subcommand `standalone_section` (netsolve yield, sinter, ...).
/// `sections`: every subcommand of the tool (sections a run skips).
void add_scene_config(CLI::App& app, const std::string& tool, const std::string& standalone_section,
                      const std::vector<std::string>& sections);

/// After a successful parse: the scene of the parsed subcommand `sub` (section `section` of tool
/// `tool`) as scene.toml's text, which open_run_dir writes into the run folder (scene_text()).
std::string scene_toml(const CLI::App& sub, const std::string& tool, const std::string& section);

/// The scene.toml text open_run_dir writes (empty: none); reset_run_state clears it (output.cpp).
std::string& scene_text();

/// scene_text() = scene_toml(sub, tool, section): call after the parse.
inline void set_scene(const CLI::App& sub, const std::string& tool, const std::string& section) {
  scene_text() = scene_toml(sub, tool, section);
}

/// The subcommands (scene-file sections) of each tool.
inline const std::vector<std::string> kNetsolveSections = {"pack", "compact", "yield", "yield-merge", "sinter-pair", "sinter"};
inline const std::vector<std::string> kDemsolveSections = {"prepare", "sinter", "compress", "vibrate", "compact", "yield"};

}  // namespace netdem::app
