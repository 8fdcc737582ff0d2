// One declaration per configuration section: a table of keys, each with its kind, allowed range,
// unit, default and a one-line meaning. The table drives the section's reader (every problem
// named with key, value and allowed range; unknown keys refused), gives its defaults (read from a
// default-constructed settings struct, so the two cannot disagree), its YAML form, the generated
// bad-input tests (test/core/support/bad_input.hpp) and the parameter tables of the docs (gear_run
// --print-parameters). Checks between keys stay explicit code after the table-driven pass.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace gear_dynamics {

class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(const std::string& what) : std::runtime_error(what) {}
};

// What a key holds. Real and Integer are numbers in a range; a RealList holds numbers each in the
// range; a TextList also accepts one text for a list of one.
enum class KeyKind { Real, Integer, Flag, Text, RealList, TextList };

// An interval of allowed numbers; an infinite bound is never included.
struct Range {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool open_lo = true, open_hi = true;
  bool contains(double x) const;
  // "[0, 0.2]", "(0, inf)"; integer bounds with every digit.
  std::string text(bool integer = false) const;
};
constexpr double kInf = std::numeric_limits<double>::infinity();
inline Range closed(double lo, double hi) { return {lo, hi, false, false}; }
inline Range open(double lo, double hi) { return {lo, hi, true, true}; }
inline Range open_closed(double lo, double hi) { return {lo, hi, true, false}; }  // (lo, hi]
inline Range closed_open(double lo, double hi) { return {lo, hi, false, true}; }  // [lo, hi)
inline Range any_number() { return {}; }

// One key as the reader, the docs and the tests see it.
struct KeySpec {
  std::string name;
  KeyKind kind = KeyKind::Real;
  Range range;                // a number, or each number of a list
  std::string unit;           // SI unit, "-" for none; empty for flags and texts
  std::string doc;            // one line
  std::size_t size = 0;       // a list of exactly this many, or 0: any number
  bool may_be_empty = false;  // a list may be [], a text ""
  std::vector<std::string> choices;  // a text: one of these, if any are given
  bool required = true;       // false: a missing key keeps its default
  bool omitted_at_default = false;  // optional, and left out of the YAML form at its default
  YAML::Node default_value;   // from the default-constructed settings struct

  bool integer() const { return kind == KeyKind::Integer; }
  bool list() const { return kind == KeyKind::RealList || kind == KeyKind::TextList; }
  // "[0, 0.2] -": the range and the unit, as the messages state them.
  std::string allowed() const;
  // What a value must be, e.g. "a number in (0, inf) m", "true or false", "a list of 3 numbers in ...".
  std::string expected() const;
  // The type as the docs name it: real, integer, bool, string, list of (2) reals, ...
  std::string type() const;
};

// A section as the docs and the tests see it. `prefix` starts every key in messages and docs:
// "monte_carlo." for a YAML section, "~" for a node's own private parameters.
struct SectionSpec {
  std::string name, prefix;
  std::vector<KeySpec> keys;
  const KeySpec* find(const std::string& key) const;
};

// A value that passed its KeySpec.
struct Value {
  double number = 0;
  bool flag = false;
  std::string text;
  std::vector<double> numbers;
  std::vector<std::string> texts;
};

// Reads the keys of one YAML map. Every problem becomes one message in `errors` that names the
// key, the value and what is allowed. A key that is missing or bad yields nothing and is not ok(),
// so the checks that depend on it can be left out instead of reporting a consequence twice.
class SectionReader {
 public:
  // `section` is the map (an undefined node counts as empty), `prefix` starts its keys in messages.
  SectionReader(const YAML::Node& section, std::string prefix, std::vector<std::string>& errors);

  // The value of `key` if it is present and as its spec allows; a missing optional key is nullopt
  // without a message.
  std::optional<Value> read(const KeySpec& key);
  // True if `key` was read and is good.
  bool ok(const std::string& key) const { return good_.count(key) > 0; }
  // A problem between keys: "<prefix><key><what>".
  void error(const std::string& key, const std::string& what);
  // Reports every key that was never read (nor named in `others`) as a typo.
  void finish(const std::vector<std::string>& others = {});

  const std::string& prefix() const { return prefix_; }
  // Numbers in messages: 12 significant digits.
  static std::string text_of(double x);

 private:
  std::optional<double> number(const KeySpec& key, const YAML::Node& v, const std::string& path);

  YAML::Node section_;
  std::string prefix_;
  std::vector<std::string>& errors_;
  std::vector<std::string> read_;  // in table order, for the list of valid keys
  std::set<std::string> good_;
};

namespace detail {
// Parses one scalar as a number; false if it is not one (booleans and strings are not).
bool as_number(const YAML::Node& n, double& out);
// A node as one line of YAML, for error messages.
std::string show(const YAML::Node& n);
// Throws one ConfigError listing every message, if there are any.
void throw_if_errors(const std::vector<std::string>& errors);
}  // namespace detail

// How a member of type T is read from a Value and written as YAML: the kind follows from the type.
// Settings types of a section (e.g. Interval) add their own specialisation next to their table.
template <class T, class = void>
struct Codec;
template <>
struct Codec<double> {
  static constexpr KeyKind kind = KeyKind::Real;
  static constexpr std::size_t size = 0;
  static void set(double& m, const Value& v) { m = v.number; }
  static YAML::Node get(double m) { return YAML::Node(m); }
};
template <class T>
struct Codec<T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>>> {
  static constexpr KeyKind kind = KeyKind::Integer;
  static constexpr std::size_t size = 0;
  static void set(T& m, const Value& v) { m = static_cast<T>(v.number); }
  static YAML::Node get(T m) { return YAML::Node(m); }
};
template <>
struct Codec<bool> {
  static constexpr KeyKind kind = KeyKind::Flag;
  static constexpr std::size_t size = 0;
  static void set(bool& m, const Value& v) { m = v.flag; }
  static YAML::Node get(bool m) { return YAML::Node(m); }
};
template <>
struct Codec<std::string> {
  static constexpr KeyKind kind = KeyKind::Text;
  static constexpr std::size_t size = 0;
  static void set(std::string& m, const Value& v) { m = v.text; }
  static YAML::Node get(const std::string& m) { return YAML::Node(m); }
};
// A YAML list in flow style ("[0.3, 0.4]"), as the shipped files write lists.
template <class T>
YAML::Node flow_list(const std::vector<T>& items) {
  YAML::Node n(YAML::NodeType::Sequence);
  for (const T& x : items) n.push_back(x);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}
template <>
struct Codec<std::vector<double>> {
  static constexpr KeyKind kind = KeyKind::RealList;
  static constexpr std::size_t size = 0;
  static void set(std::vector<double>& m, const Value& v) { m = v.numbers; }
  static YAML::Node get(const std::vector<double>& m) { return flow_list(m); }
};
template <>
struct Codec<std::vector<std::string>> {
  static constexpr KeyKind kind = KeyKind::TextList;
  static constexpr std::size_t size = 0;
  static void set(std::vector<std::string>& m, const Value& v) { m = v.texts; }
  static YAML::Node get(const std::vector<std::string>& m) { return flow_list(m); }
};

// The member a key is stored in, e.g. GD_MEMBER(gear.density): works on const and non-const.
#define GD_MEMBER(path) [](auto& s) -> auto& { return s.path; }

// The declaration of one section of settings struct S: its keys in order, each bound to a member.
template <class S>
class Section {
 public:
  Section(std::string name, std::string prefix) : name_(std::move(name)), prefix_(std::move(prefix)) {}

  // A number or a list of numbers, in `range` [unit].
  template <class Member>
  Section& key(const char* name, Member member, Range range, const char* unit, const char* doc) {
    using T = std::decay_t<decltype(member(std::declval<S&>()))>;
    KeySpec spec;
    spec.name = name;
    spec.kind = Codec<T>::kind;
    spec.range = range;
    spec.unit = unit;
    spec.doc = doc;
    spec.size = Codec<T>::size;
    spec.default_value = Codec<T>::get(member(std::as_const(defaults_)));
    keys_.push_back({spec, [member](S& s, const Value& v) { Codec<T>::set(member(s), v); },
                     [member](const S& s) { return Codec<T>::get(member(s)); }});
    return *this;
  }
  // A flag, a text or a list of texts.
  template <class Member>
  Section& key(const char* name, Member member, const char* doc) {
    return key(name, member, Range{}, "", doc);
  }
  // Modifiers of the key declared last.
  Section& optional() { return keys_.back().spec.required = false, *this; }
  Section& may_be_empty() { return keys_.back().spec.may_be_empty = true, *this; }
  // Optional and left out of to_yaml() while at its default: a key of a model that is not the
  // default leaves the default runs' configuration text (and so their bags) as they were.
  Section& omitted_at_default() {
    keys_.back().spec.required = false;
    return keys_.back().spec.omitted_at_default = true, *this;
  }
  Section& one_of(std::vector<std::string> choices) { return keys_.back().spec.choices = std::move(choices), *this; }

  // Reads every key of the table from `in` into `out` (bad keys leave their member alone).
  void read(SectionReader& in, S& out) const {
    for (const Key& k : keys_)
      if (const auto v = in.read(k.spec)) k.set(out, *v);
  }
  // The section as a YAML map, in table order.
  YAML::Node to_yaml(const S& s) const {
    YAML::Node n(YAML::NodeType::Map);
    for (const Key& k : keys_) {
      YAML::Node v = k.get(s);
      if (k.spec.omitted_at_default && YAML::Dump(v) == YAML::Dump(k.spec.default_value)) continue;
      n[k.spec.name] = v;
    }
    return n;
  }
  SectionSpec spec() const {
    SectionSpec out{name_, prefix_, {}};
    for (const Key& k : keys_) out.keys.push_back(k.spec);
    return out;
  }
  const std::string& name() const { return name_; }
  const std::string& prefix() const { return prefix_; }

 private:
  struct Key {
    KeySpec spec;
    std::function<void(S&, const Value&)> set;
    std::function<YAML::Node(const S&)> get;
  };
  std::string name_, prefix_;
  std::vector<Key> keys_;
  S defaults_{};
};

}  // namespace gear_dynamics
