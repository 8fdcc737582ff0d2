// The seam of gear_analyze: each subcommand is one Subcommand in a file of its own
// (src/tools/analyze/<name>.cpp) and one line in main.cpp's table (doc/architecture.md, recipes).
// A subcommand declares its options on its own CLI::App, each default written once beside the
// option, and runs with the options the main parsed. Private to the tool.
#pragma once

#include <memory>
#include <string>

#include "../cli.hpp"

namespace gear_dynamics::tools::analyze {

// The options every subcommand takes (they may stand before or after the subcommand's name).
struct Common {
  ModelOptions model;
  std::string output = "gear_analyze";  // CSV files PREFIX_<name>.csv
  bool png = false;                     // then draw PREFIX_*.png with scripts/plot_dynamics.py
};

class Subcommand {
 public:
  virtual ~Subcommand() = default;
  virtual std::string name() const = 0;
  // One line for --help.
  virtual std::string description() const = 0;
  // Declares the subcommand's options on `app`, bound to members of the subcommand.
  virtual void add_options(CLI::App& app) = 0;
  // Runs after parsing: writes PREFIX_*.csv, prints a summary; returns the exit status. Bad input
  // it finds only now (e.g. against the model) throws std::runtime_error naming the option.
  virtual int run(const Common& common) = 0;
};

// One factory per subcommand, each defined in its own file and listed in main.cpp's table.
std::unique_ptr<Subcommand> make_spectrum();
std::unique_ptr<Subcommand> make_stiffness();
std::unique_ptr<Subcommand> make_poincare();
std::unique_ptr<Subcommand> make_bifurcation();
std::unique_ptr<Subcommand> make_lyapunov();
std::unique_ptr<Subcommand> make_safety();
std::unique_ptr<Subcommand> make_monitor();

}  // namespace gear_dynamics::tools::analyze
