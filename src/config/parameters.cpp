#include "gear_dynamics/config/parameters.hpp"

#include <cmath>
#include <sstream>

#include "gear_dynamics/config/aggregator_settings.hpp"
#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/simulator_settings.hpp"

namespace gear_dynamics {

std::vector<SectionSpec> parameter_sections() {
  std::vector<SectionSpec> all;
  for (const Section<ModelConfig>& s : model_sections()) all.push_back(s.spec());
  all.push_back(batch_section().spec());
  all.push_back(simulator_section().spec());
  all.push_back(analysis_section().spec());
  all.push_back(aggregator_section().spec());
  return all;
}

namespace {

// A default as the docs show it: numbers with 12 significant digits, integers whole.
std::string shown(const KeySpec& k, const YAML::Node& v) {
  if (v.IsSequence()) {
    std::string out;
    for (const YAML::Node& x : v) out += (out.empty() ? "" : ", ") + shown(k, x);
    return "[" + out + "]";
  }
  double x;
  if (k.kind != KeyKind::Flag && k.kind != KeyKind::Text && k.kind != KeyKind::TextList && detail::as_number(v, x))
    return k.integer() ? std::to_string(static_cast<long long>(x)) : SectionReader::text_of(x);
  return v.Scalar().empty() ? "\"\"" : v.Scalar();
}

std::string allowed(const KeySpec& k) {
  const std::string range = std::isinf(k.range.lo) && std::isinf(k.range.hi) ? "finite" : k.range.text(k.integer());
  switch (k.kind) {
    case KeyKind::Real:
    case KeyKind::Integer:
      return range;
    case KeyKind::Flag:
      return "true, false";
    case KeyKind::Text:
      if (!k.choices.empty()) {
        std::string list;
        for (const std::string& c : k.choices) list += (list.empty() ? "" : ", ") + c;
        return list;
      }
      return k.may_be_empty ? "any string" : "non-empty";
    case KeyKind::RealList:
      return std::string(k.size ? "" : k.may_be_empty ? "any length, " : "non-empty, ") + "each " + (range == "finite" ? range : "in " + range);
    case KeyKind::TextList:
      return "non-empty, each non-empty";
  }
  return "";
}

}  // namespace

std::string parameter_table(const SectionSpec& section) {
  std::ostringstream out;
  out << "| key | type | unit | default | allowed | meaning |\n|---|---|---|---|---|---|\n";
  for (const KeySpec& k : section.keys) {
    // A required key whose default is empty where empty is refused (~folders) has none to show.
    const YAML::Node& d = k.default_value;
    const bool no_default = !k.may_be_empty && (d.IsSequence() ? d.size() == 0 : d.Scalar().empty());
    out << "| `" << section.prefix << k.name << "` | " << k.type() << " | " << k.unit << " | "
        << (no_default ? "required" : "`" + shown(k, k.default_value) + "`") << (k.required ? "" : " (optional)")
        << " | " << allowed(k) << " | " << k.doc << " |\n";
  }
  return out.str();
}

}  // namespace gear_dynamics
