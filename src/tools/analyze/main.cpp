// gear_analyze: the nonlinear-dynamics tools of doc/nonlinear-dynamics.md as one subcommand each.
// Writes CSV (SI units) with a common prefix and prints a summary; --png draws the figures with
// scripts/plot_dynamics.py. No ROS master needed. The subcommands are listed in kSubcommands.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "subcommand.hpp"

namespace analyze = gear_dynamics::tools::analyze;

namespace {

// Every subcommand, in the order of --help: a new one is one file and one line here.
constexpr std::unique_ptr<analyze::Subcommand> (*kSubcommands[])() = {
    analyze::make_spectrum, analyze::make_stiffness, analyze::make_poincare,
    analyze::make_bifurcation, analyze::make_lyapunov, analyze::make_safety, analyze::make_monitor,
};

void draw(const std::string& command, const analyze::Common& c) {
  namespace fs = std::filesystem;
  std::cout.flush();
  std::fflush(stdout);  // the summary before the plot script's lines
  const fs::path script = fs::path(gear_dynamics::tools::config_dir()).parent_path() / "scripts" / "plot_dynamics.py";
  if (!fs::exists(script)) throw std::runtime_error("--png: cannot find " + script.string());
  const std::string cmd = "/usr/bin/python3 '" + script.string() + "' " + command + " '" + c.output + "'";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("--png: '" + cmd + "' failed");
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app("Nonlinear-dynamics tools for the spur-gear model (doc/nonlinear-dynamics.md).", "gear_analyze");
  app.require_subcommand(1);
  app.fallthrough();  // the common options below may follow the subcommand
  analyze::Common common;
  gear_dynamics::tools::add_model_options(app, common.model);
  app.add_option("--output", common.output, "CSV files PREFIX_<name>.csv")->type_name("PREFIX")->capture_default_str();
  app.add_flag("--png", common.png, "then draw PREFIX_*.png with scripts/plot_dynamics.py");
  std::vector<std::unique_ptr<analyze::Subcommand>> commands;
  for (const auto make : kSubcommands) {
    commands.push_back(make());
    analyze::Subcommand& s = *commands.back();
    s.add_options(*app.add_subcommand(s.name(), s.description()));
  }
  gear_dynamics::tools::parse_or_exit(app, argc, argv);
  const std::string chosen = app.get_subcommands().front()->get_name();
  for (const auto& s : commands)
    if (s->name() == chosen) {
      const int rc = s->run(common);
      if (rc == 0 && common.png) draw(chosen, common);
      return rc;
    }
  return 1;  // CLI11 accepts only the subcommands above
} catch (const std::exception& e) {
  std::cerr << "gear_analyze: " << e.what() << "\n";
  return 1;
}
