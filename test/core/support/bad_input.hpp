// Bad configuration generated key by key from each section's declaration (section.hpp: the key's
// kind, list length and allowed range) and a value the validator accepts: the cases a validator
// must refuse with one message naming the key, the value and the range. Shared by the gtests of
// every validator (model, batch, simulator, analysis, aggregator).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "gear_dynamics/config/section.hpp"

namespace bad_input {

namespace gd = gear_dynamics;

using Range = gd::Range;

// Categories of the fault suite's summary table.
constexpr const char* kMissing = "missing";
constexpr const char* kWrongType = "wrong_type";
constexpr const char* kNaN = "nan";
constexpr const char* kInf = "inf";
constexpr const char* kNonPositive = "negative_or_zero";
constexpr const char* kOutOfRange = "out_of_range";
constexpr const char* kUnknownKey = "unknown_key";
constexpr const char* kInconsistent = "inconsistent";

struct Case {
  std::string category;
  std::string section;          // the declared section's name
  std::string location;         // the map in the YAML root that holds it ("" = the root itself)
  std::string prefix;           // how messages name its keys ("monte_carlo.", "~")
  std::string key;
  int index = -1;               // list element changed, or -1 for the whole value
  std::optional<YAML::Node> value;  // nothing: the key is removed; else its new value
  std::string unknown_key;      // set: this key is added (a typo) instead
  std::string variant;          // tells cases of one key and category apart
  std::optional<Range> range;   // the key's allowed range, when it holds numbers: the message must state it

  std::string path() const {
    return prefix + (unknown_key.empty() ? key : unknown_key) + (index >= 0 ? "[" + std::to_string(index) + "]" : "");
  }
  std::string whole_path() const { return prefix + key; }
  // A gtest-safe name: category__section_key_variant.
  std::string name() const {
    std::string n = category + "__" + section + "_" + (unknown_key.empty() ? key : unknown_key) +
                    (index >= 0 ? "_" + std::to_string(index) : "") + (variant.empty() ? "" : "_" + variant);
    for (char& c : n)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    return n;
  }
  void apply(YAML::Node& root) const {
    YAML::Node s = location.empty() ? root : root[location];
    if (!unknown_key.empty()) {
      s[unknown_key] = *value;
    } else if (!value) {
      s.remove(key);
    } else if (index >= 0) {
      s[key][index] = *value;
    } else {
      s[key] = *value;
    }
  }
};

inline std::string format(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

inline bool is_number(const YAML::Node& n) {
  if (!n.IsScalar() || n.Scalar() == "true" || n.Scalar() == "false") return false;
  try {
    n.as<double>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

// Values just outside the range (at an open bound, one step past a closed one), and -1 and 0
// where the range says a sign is meaningless: each with its category.
inline std::vector<std::pair<std::string, double>> outside(const Range& r, bool integer) {
  std::vector<std::pair<std::string, double>> out;
  const auto add = [&out](const char* category, double v) {
    for (const auto& o : out)
      if (o.second == v) return;
    out.push_back({category, v});
  };
  const auto past = [integer](double bound, double dir) {
    return integer ? bound + dir : bound + dir * std::max(std::abs(bound) * 1e-6, 1e-12);
  };
  if (std::isfinite(r.lo)) {
    const double below = r.open_lo ? r.lo : past(r.lo, -1);
    add(r.lo >= 0 && below <= 0 ? kNonPositive : kOutOfRange, below);
    if (r.lo >= 0) add(kNonPositive, -1.0);
    if (r.lo > 0) add(kNonPositive, 0.0);
  }
  if (std::isfinite(r.hi)) add(kOutOfRange, r.open_hi ? r.hi : past(r.hi, 1));
  return out;
}

// The cases for one declared key of `section`, held in the map `location` of the root, whose
// value `good` the validator accepts (the shipped one, or the default of an optional key).
inline std::vector<Case> key_cases(const gd::SectionSpec& section, const std::string& location, const gd::KeySpec& k,
                                   const YAML::Node& good) {
  using Kind = gd::KeyKind;
  const bool numbers = k.kind == Kind::Real || k.kind == Kind::Integer || k.kind == Kind::RealList;
  const std::optional<Range> range = numbers ? std::optional<Range>(k.range) : std::nullopt;
  std::vector<Case> cases;
  const auto add = [&](const char* category, int index, const YAML::Node& v, const std::string& variant) {
    cases.push_back(Case{category, section.name, location, section.prefix, k.name, index, YAML::Clone(v), "", variant, range});
  };
  if (k.required) cases.push_back(Case{kMissing, section.name, location, section.prefix, k.name, -1, std::nullopt, "", "", range});
  cases.push_back(Case{kUnknownKey, section.name, location, section.prefix, k.name, -1, YAML::Clone(good), k.name + "_", "",
                       std::nullopt});
  const YAML::Node map = YAML::Load("{a: 1}");
  if (k.list()) {
    if (k.kind == Kind::RealList) add(kWrongType, -1, YAML::Node("not_a_list"), "scalar");
    add(kWrongType, -1, map, "map");
    if (!k.may_be_empty) add(kWrongType, -1, YAML::Load("[]"), "empty");
    if (k.size) {
      YAML::Node longer = YAML::Clone(good);
      longer.push_back(good[0]);
      add(kWrongType, -1, longer, "length");
    }
    if (good.size() == 0) return cases;
  }
  const int index = k.list() && good.IsSequence() ? 0 : -1;
  switch (k.kind) {
    case Kind::Real:
    case Kind::Integer:
    case Kind::RealList:
      add(kWrongType, index, YAML::Node("not_a_number"), "string");
      add(kWrongType, index, YAML::Node(true), "bool");
      if (!k.list()) add(kWrongType, index, YAML::Load("[1, 2]"), "list");
      add(kNaN, index, YAML::Load(".nan"), "");
      add(kInf, index, YAML::Load(".inf"), "pos");
      add(kInf, index, YAML::Load("-.inf"), "neg");
      if (k.integer()) add(kWrongType, index, YAML::Node((std::isfinite(k.range.lo) ? k.range.lo + 1 : 1) + 0.5), "fraction");
      for (const auto& [category, v] : outside(k.range, k.integer())) add(category.c_str(), index, YAML::Node(v), format(v));
      break;
    case Kind::Flag:
      add(kWrongType, index, YAML::Node("maybe"), "string");
      add(kWrongType, index, YAML::Node(2), "number");
      break;
    case Kind::Text:
      add(kWrongType, index, map, "map");
      add(kWrongType, index, YAML::Load("[a, b]"), "list");
      if (!k.may_be_empty) add(kWrongType, index, YAML::Node(""), "empty");
      if (!k.choices.empty()) add(kOutOfRange, index, YAML::Node("not_a_choice"), "choice");
      break;
    case Kind::TextList:
      add(kWrongType, -1, YAML::Node(""), "empty_string");
      if (index >= 0) add(kWrongType, index, map, "element_map");
      break;
  }
  return cases;
}

// gtest prints a case by its key and value.
inline void PrintTo(const Case& c, std::ostream* os) {
  *os << c.path() << " = ";
  if (c.value) {
    YAML::Emitter e;
    e << YAML::Flow << *c.value;
    *os << e.c_str();
  } else {
    *os << "(removed)";
  }
}

// Every number in a message line (with inf and nan), in order.
inline std::vector<double> numbers_in(const std::string& line) {
  // YAML's spellings (.nan, -.inf) too.
  static const std::regex number(R"([-+]?(?:\.?(?:inf|nan)(?![a-z_])|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?))",
                                 std::regex::icase);
  std::vector<double> out;
  for (auto it = std::sregex_iterator(line.begin(), line.end(), number); it != std::sregex_iterator(); ++it) {
    std::string t = it->str();
    const auto dot = t.find(".i") != std::string::npos ? t.find(".i") : t.find(".n");
    if (dot != std::string::npos) t.erase(dot, 1);
    out.push_back(std::strtod(t.c_str(), nullptr));
  }
  return out;
}

inline bool same(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)) + 1e-300;
}

// The interval a message line states ("[0, 0.001]", "(0, inf)"), if any.
inline std::optional<Range> stated_range(const std::string& line) {
  static const std::regex interval(R"(([\[(])\s*([-+.\w]+)\s*,\s*([-+.\w]+)\s*([\])]))");
  std::smatch m;
  if (!std::regex_search(line, m, interval)) return std::nullopt;
  const auto number = [](const std::string& s, double& out) {
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return end != s.c_str() && *end == '\0';
  };
  double lo, hi;
  if (!number(m[2].str(), lo) || !number(m[3].str(), hi)) return std::nullopt;
  return Range{lo, hi, m[1] == "(", m[4] == ")"};
}

// True if `line` names `path` as a whole key (not as the prefix of a longer key).
inline bool names(const std::string& line, const std::string& path) {
  for (auto p = line.find(path); p != std::string::npos; p = line.find(path, p + 1)) {
    const std::size_t e = p + path.size();
    const bool word_start = p == 0 || !(std::isalnum(static_cast<unsigned char>(line[p - 1])) || line[p - 1] == '_');
    const bool word_end = e == line.size() || !(std::isalnum(static_cast<unsigned char>(line[e])) || line[e] == '_');
    if (word_start && word_end) return true;
  }
  return false;
}

// The error lines of a validator's message (its first line is a heading when it holds several).
inline std::vector<std::string> error_lines(const std::string& what) {
  std::vector<std::string> lines;
  std::istringstream in(what);
  for (std::string l; std::getline(in, l);) {
    const auto b = l.find_first_not_of(' ');
    if (b != std::string::npos) lines.push_back(l.substr(b));
  }
  if (lines.size() > 1) lines.erase(lines.begin());
  return lines;
}

// What is wrong with how `error` (the validator's message, "" if it accepted) handles `c`: "" if
// it is one line that names the key, the value and the allowed range (c.range, when known).
inline std::string judge(const Case& c, const std::string& error) {
  if (error.empty()) return "accepted";
  const std::vector<std::string> lines = error_lines(error);
  if (lines.size() != 1) return "expected one error line, got " + std::to_string(lines.size()) + ":\n" + error;
  const std::string& line = lines[0];
  // A list element may be named by its index or by the list.
  const std::string whole = c.whole_path();
  const std::string path = names(line, c.path()) || c.index < 0 || !names(line, whole) ? c.path() : whole;
  if (!names(line, path)) return "does not name " + c.path() + ": " + line;
  if (c.category == kUnknownKey) {
    return line.find("not a known key") != std::string::npos ? "" : "does not say the key is unknown: " + line;
  }
  if (!c.value) {
    if (line.find("missing") == std::string::npos) return "does not say the key is missing: " + line;
  } else if (is_number(*c.value)) {
    const double v = c.value->as<double>();
    bool named = false;
    for (double x : numbers_in(line.substr(line.find(path) + path.size()))) named = named || same(x, v);
    if (!named) return "does not name the value " + format(v) + ": " + line;
  } else {
    YAML::Emitter e;
    e << YAML::Flow << *c.value;
    if (line.find(e.c_str()) == std::string::npos) return std::string("does not name the value ") + e.c_str() + ": " + line;
  }
  const std::size_t allowed = std::min(line.find("allowed"), line.find("expected"));
  if (allowed == std::string::npos) return "does not state what is allowed: " + line;
  if (const auto& range = c.range) {
    const std::optional<Range> s = stated_range(line.substr(allowed));
    if (!s) return "does not state the range: " + line;
    const auto close = [](double a, double b) { return a == b || std::abs(a - b) <= 1e-5 * std::abs(b); };
    if (!close(s->lo, range->lo) || !close(s->hi, range->hi) || s->open_lo != range->open_lo ||
        s->open_hi != range->open_hi)
      return "states a range other than the schema's: " + line;
  }
  return "";
}

// Runs `parse` on `root` and returns its ConfigError message, "" if it accepted; anything else it
// throws is turned into a message that fails `judge`.
template <class Error>
std::string error_of(const std::function<void(const YAML::Node&)>& parse, const YAML::Node& root) {
  try {
    parse(root);
    return "";
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("\nthrew something other than a configuration error: ") + e.what() + "\n";
  }
}

}  // namespace bad_input
