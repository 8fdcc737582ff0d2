#include "gear_dynamics/config/section_reader.hpp"

#include <cmath>
#include <sstream>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

SectionReader::SectionReader(const YAML::Node& section, std::string name, std::vector<std::string>& errors)
    : section_(section), name_(std::move(name)), errors_(errors) {}

std::string SectionReader::text_of(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

namespace {

// "[lo, hi] unit"; an infinite bound is never included.
std::string range_text(double lo, double hi, bool open_lo, bool open_hi, bool integer, const std::string& unit) {
  return ((open_lo || std::isinf(lo)) ? "(" : "[") + SectionReader::text_of(lo) + ", " + SectionReader::text_of(hi) +
         ((open_hi || std::isinf(hi)) ? ")" : "]") + (integer ? " (integer) " : " ") + unit;
}

}  // namespace

std::optional<YAML::Node> SectionReader::get(const char* key, const std::string& allowed) {
  read_.insert(key);
  const YAML::Node v = section_.IsMap() ? section_[key] : YAML::Node();
  if (!v.IsDefined() || v.IsNull()) {
    error(key, " is missing; " + allowed);
    return std::nullopt;
  }
  return v;
}

std::optional<double> SectionReader::number(const char* key, double lo, double hi, bool integer,
                                            const std::string& unit, bool open_lo, bool open_hi) {
  const std::string range = range_text(lo, hi, open_lo, open_hi, integer, unit);
  const auto v = get(key, "allowed " + range);
  if (!v) return std::nullopt;
  double x;
  if (!detail::as_number(*v, x)) {
    error(key, " = " + detail::show(*v) + " has the wrong type: expected a number in " + range);
  } else if (!std::isfinite(x) || (open_lo ? x <= lo : x < lo) || (open_hi ? x >= hi : x > hi)) {
    error(key, " = " + text_of(x) + " is out of range; allowed " + range);
  } else if (integer && x != std::floor(x)) {
    error(key, " = " + text_of(x) + " is not an integer; allowed " + range);
  } else {
    return x;
  }
  return std::nullopt;
}

std::optional<bool> SectionReader::flag(const char* key) {
  const auto v = get(key, "expected true or false");
  bool b;
  if (v && v->IsScalar() && YAML::convert<bool>::decode(*v, b)) return b;
  if (v) error(key, " = " + detail::show(*v) + " has the wrong type: expected true or false");
  return std::nullopt;
}

std::optional<std::string> SectionReader::text(const char* key) {
  const auto v = get(key, "expected a non-empty path");
  if (v && v->IsScalar() && !v->Scalar().empty()) return v->Scalar();
  if (v) error(key, " = " + detail::show(*v) + " is not allowed: expected a non-empty path");
  return std::nullopt;
}

std::optional<std::vector<double>> SectionReader::numbers(const char* key, double lo, double hi,
                                                          const std::string& unit, std::size_t size) {
  const std::string range = range_text(lo, hi, false, false, false, unit);
  const std::string expected =
      (size ? "a list of " + std::to_string(size) + " numbers in " : "a non-empty list of numbers in ") + range;
  const auto v = get(key, "expected " + expected);
  if (!v) return std::nullopt;
  if (!v->IsSequence() || v->size() == 0 || (size && v->size() != size)) {
    error(key, " = " + detail::show(*v) + " is not allowed: expected " + expected);
    return std::nullopt;
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < v->size(); ++i) {
    const std::string item = std::string(key) + "[" + std::to_string(i) + "]";
    double x;
    if (!detail::as_number((*v)[i], x)) {
      error(item, " = " + detail::show((*v)[i]) + " has the wrong type: expected a number in " + range);
    } else if (!std::isfinite(x) || x < lo || x > hi) {
      error(item, " = " + text_of(x) + " is out of range; allowed " + range);
    } else {
      out.push_back(x);
    }
  }
  if (out.size() != v->size()) return std::nullopt;
  return out;
}

void SectionReader::error(const std::string& key, const std::string& what) {
  errors_.push_back(name_ + "." + key + what);
}

void SectionReader::finish() {
  if (!section_.IsMap()) return;
  for (const auto& kv : section_) {
    const std::string key = kv.first.as<std::string>();
    if (read_.count(key)) continue;
    std::string valid;
    for (const std::string& k : read_) valid += (valid.empty() ? "" : ", ") + k;
    error(key, " is not a known key (a typo?); valid keys: " + valid);
  }
}

}  // namespace gear_dynamics
