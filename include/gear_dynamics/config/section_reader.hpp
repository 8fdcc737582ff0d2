// Reading one YAML section key by key, for the validators that are not schema-driven (the batch's
// monte_carlo, the simulator's simulator and the aggregator's analysis section). Every problem becomes one message that
// names the key, the value and what is allowed; a missing key names what is allowed too; keys never
// read are reported as typos by finish(). A key that is missing or bad yields nullopt, so the caller
// can leave out the checks that depend on it instead of reporting a consequence as a second error.
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace gear_dynamics {

class SectionReader {
 public:
  // `section` is the map (an undefined node counts as empty), `name` its name in messages.
  SectionReader(const YAML::Node& section, std::string name, std::vector<std::string>& errors);

  // A number in [lo, hi] (excluding lo if open_lo, hi if open_hi), a whole one if `integer`.
  std::optional<double> number(const char* key, double lo, double hi, bool integer, const std::string& unit,
                               bool open_lo = false, bool open_hi = false);
  std::optional<bool> flag(const char* key);
  std::optional<std::string> text(const char* key);  // a non-empty string
  // A list of finite numbers in [lo, hi]: `size` of them, or any number but none if size is 0.
  std::optional<std::vector<double>> numbers(const char* key, double lo, double hi, const std::string& unit,
                                             std::size_t size = 0);

  // A problem between keys: "<name>.<key><what>".
  void error(const std::string& key, const std::string& what);
  // Reports the keys never read as typos.
  void finish();

  // Formatting shared by the messages (12 significant digits).
  static std::string text_of(double x);

 private:
  // The value of `key`, or nothing (reported as missing, with `allowed`) if absent or null.
  std::optional<YAML::Node> get(const char* key, const std::string& allowed);

  YAML::Node section_;
  std::string name_;
  std::vector<std::string>& errors_;
  std::set<std::string> read_;
};

}  // namespace gear_dynamics
