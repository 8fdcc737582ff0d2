// The command-line tools' shared parts (gear_run, gear_analyze, gear_bench): one argument parser,
// CLI11, whose declarations also give --help; and the options that pick the model configuration
// (read by the core's config/model_files.hpp). Private to the tools, not a layer of the library.
#pragma once

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/model_files.hpp"

namespace gear_dynamics::tools {

// Parses argv into `app`'s options. --help prints the generated help and exits 0; a bad command
// line prints "NAME: reason (NAME --help)" and exits 1, as every other error of the tools.
inline void parse_or_exit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    std::exit(0);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s (%s --help)\n", app.get_name().c_str(), e.what(), app.get_name().c_str());
    std::exit(1);
  }
}

// A number in [lo, hi] (hi omitted: no upper bound). CLI11 refuses any other value as
// "--name: VALUE is out of range; allowed ...", naming the option, the value and the range.
inline CLI::Validator in_range(double lo, double hi = std::numeric_limits<double>::infinity()) {
  std::ostringstream allowed;
  if (std::isinf(hi)) allowed << ">= " << lo;
  else allowed << "[" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, range = allowed.str()](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return text + " is not a number";
        if (!(v >= lo && v <= hi)) return text + " is out of range; allowed " + range;
        return "";
      },
      allowed.str());
}

// A number > 0.
inline CLI::Validator positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return text + " is not a number";
        if (!(v > 0.0)) return text + " is out of range; allowed > 0";
        return "";
      },
      "> 0");
}

// One value per occurrence, repeatable: --config a.yaml --config b.yaml.
inline CLI::Option* add_repeatable(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                                   const std::string& description) {
  return app.add_option(name, values, description)->type_size(1)->allow_extra_args(false)->take_all();
}

// The model configuration's options and files (config/model_files.hpp), by their tools:: names.
using gear_dynamics::ModelOptions;
using gear_dynamics::apply_set;
using gear_dynamics::config_dir;
using gear_dynamics::drop_late_snapshots;
using gear_dynamics::model_yaml;

inline void add_model_options(CLI::App& app, ModelOptions& o) {
  add_repeatable(app, "--config", o.files, "YAML file overlaid on the defaults (repeatable)")->type_name("FILE");
  add_repeatable(app, "--set", o.sets, "override one parameter, e.g. --set run.duration=0.1 (repeatable)")
      ->type_name("SEC.KEY=VAL");
  app.add_option("--mu", o.mu, "friction coefficient (default: gear_pair.friction_coefficient)")->type_name("X");
}

}  // namespace gear_dynamics::tools
