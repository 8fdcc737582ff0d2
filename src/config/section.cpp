#include "gear_dynamics/config/section.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gear_dynamics {

namespace detail {

std::string show(const YAML::Node& n) {
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

bool as_number(const YAML::Node& n, double& out) {
  if (!n.IsScalar()) return false;
  const std::string& s = n.Scalar();
  if (s == "true" || s == "false" || s == "True" || s == "False") return false;
  try {
    out = n.as<double>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

void throw_if_errors(const std::vector<std::string>& errors) {
  if (errors.empty()) return;
  std::string all = "invalid configuration:";
  for (const auto& m : errors) all += "\n  " + m;
  throw ConfigError(all);
}

}  // namespace detail

namespace {

std::string number_text(double x, bool integer) {
  std::ostringstream s;
  s.precision(integer ? 17 : 12);
  s << x;
  return s.str();
}

}  // namespace

bool Range::contains(double x) const {
  return (open_lo ? x > lo : x >= lo) && (open_hi ? x < hi : x <= hi);
}

std::string Range::text(bool integer) const {
  return ((open_lo || std::isinf(lo)) ? "(" : "[") + number_text(lo, integer) + ", " + number_text(hi, integer) +
         ((open_hi || std::isinf(hi)) ? ")" : "]");
}

std::string KeySpec::allowed() const {
  return range.text(integer()) + (integer() ? " (integer)" : "") + (unit.empty() ? "" : " " + unit);
}

std::string KeySpec::expected() const {
  switch (kind) {
    case KeyKind::Real:
    case KeyKind::Integer:
      return "a number in " + allowed();
    case KeyKind::Flag:
      return "true or false";
    case KeyKind::Text:
      if (!choices.empty()) {
        std::string list;
        for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
        return "one of " + list;
      }
      return may_be_empty ? "a string" : "a non-empty string";
    case KeyKind::RealList:
      return (size ? "a list of " + std::to_string(size) + " numbers in "
                   : may_be_empty ? "a list of numbers in " : "a non-empty list of numbers in ") + allowed();
    case KeyKind::TextList:
      return "a non-empty string or a non-empty list of them";
  }
  return "";
}

std::string KeySpec::type() const {
  switch (kind) {
    case KeyKind::Real: return "real";
    case KeyKind::Integer: return "integer";
    case KeyKind::Flag: return "bool";
    case KeyKind::Text: return "string";
    case KeyKind::RealList: return size ? "list of " + std::to_string(size) + " reals" : "list of reals";
    case KeyKind::TextList: return "string or list of strings";
  }
  return "";
}

const KeySpec* SectionSpec::find(const std::string& key) const {
  for (const KeySpec& k : keys)
    if (k.name == key) return &k;
  return nullptr;
}

SectionReader::SectionReader(const YAML::Node& section, std::string prefix, std::vector<std::string>& errors)
    : section_(section), prefix_(std::move(prefix)), errors_(errors) {}

std::string SectionReader::text_of(double x) { return number_text(x, false); }

void SectionReader::error(const std::string& key, const std::string& what) { errors_.push_back(prefix_ + key + what); }

// A number as `key` allows it, or nothing (reported under `path`, the key or a list element).
std::optional<double> SectionReader::number(const KeySpec& key, const YAML::Node& v, const std::string& path) {
  double x;
  if (!detail::as_number(v, x)) {
    error(path, " = " + detail::show(v) + " has the wrong type: expected a number in " + key.allowed());
    return std::nullopt;
  }
  const std::string what = " = " + number_text(x, key.integer());
  if (!std::isfinite(x)) {
    error(path, what + " is not finite; allowed " + key.allowed());
  } else if (key.integer() && x != std::floor(x)) {
    error(path, what + " is not an integer; allowed " + key.allowed());
  } else if (!key.range.contains(x)) {
    error(path, what + " is out of range; allowed " + key.allowed());
  } else {
    return x;
  }
  return std::nullopt;
}

std::optional<Value> SectionReader::read(const KeySpec& key) {
  read_.push_back(key.name);
  const YAML::Node v = section_.IsMap() ? section_[key.name] : YAML::Node();
  if (!v.IsDefined() || v.IsNull()) {
    if (!key.required) return std::nullopt;
    const bool number = key.kind == KeyKind::Real || key.kind == KeyKind::Integer;
    error(key.name, number ? " is missing; allowed " + key.allowed() : " is missing; expected " + key.expected());
    return std::nullopt;
  }
  Value out;
  const auto wrong = [&](const char* how) {
    error(key.name, " = " + detail::show(v) + how + key.expected());
    return std::nullopt;
  };
  switch (key.kind) {
    case KeyKind::Real:
    case KeyKind::Integer: {
      const auto x = number(key, v, key.name);
      if (!x) return std::nullopt;
      out.number = *x;
      break;
    }
    case KeyKind::Flag:
      if (!v.IsScalar() || !YAML::convert<bool>::decode(v, out.flag)) return wrong(" has the wrong type: expected ");
      break;
    case KeyKind::Text:
      if (!v.IsScalar()) return wrong(" has the wrong type: expected ");
      if (v.Scalar().empty() && !key.may_be_empty) return wrong(" is not allowed: expected ");
      if (!key.choices.empty() && std::find(key.choices.begin(), key.choices.end(), v.Scalar()) == key.choices.end())
        return wrong(" is not allowed: expected ");
      out.text = v.Scalar();
      break;
    case KeyKind::RealList: {
      if (!v.IsSequence()) return wrong(" has the wrong type: expected ");
      if ((key.size && v.size() != key.size) || (v.size() == 0 && !key.may_be_empty))
        return wrong(" is not allowed: expected ");
      bool all = true;
      for (std::size_t i = 0; i < v.size(); ++i) {
        const auto x = number(key, v[i], key.name + "[" + std::to_string(i) + "]");
        if (x) out.numbers.push_back(*x);
        all = all && x;
      }
      if (!all) return std::nullopt;
      break;
    }
    case KeyKind::TextList: {
      if (v.IsScalar() && !v.Scalar().empty()) {
        out.texts.push_back(v.Scalar());
        break;
      }
      if (!v.IsSequence()) return wrong(v.IsScalar() ? " is not allowed: expected " : " has the wrong type: expected ");
      if (v.size() == 0) return wrong(" is not allowed: expected ");
      bool all = true;
      for (std::size_t i = 0; i < v.size(); ++i) {
        const bool good = v[i].IsScalar() && !v[i].Scalar().empty();
        if (good) out.texts.push_back(v[i].Scalar());
        else error(key.name + "[" + std::to_string(i) + "]", " = " + detail::show(v[i]) + " is not allowed: expected a non-empty string");
        all = all && good;
      }
      if (!all) return std::nullopt;
      break;
    }
  }
  good_.insert(key.name);
  return out;
}

void SectionReader::finish(const std::vector<std::string>& others) {
  if (!section_.IsMap()) return;
  std::vector<std::string> known = read_;
  known.insert(known.end(), others.begin(), others.end());
  std::string valid;
  for (const std::string& k : known) valid += (valid.empty() ? "" : ", ") + k;
  for (const auto& kv : section_) {
    const std::string key = kv.first.as<std::string>();
    bool is_known = false;
    for (const std::string& k : known) is_known = is_known || k == key;
    if (!is_known) error(key, " is not a known key (a typo?); valid keys: " + valid);
  }
}

}  // namespace gear_dynamics
