#include "gear_dynamics/config/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "gear_dynamics/config/batch_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/model/gear_pair.hpp"

namespace gear_dynamics {

namespace {

constexpr int kMaxCount = 10000;        // values per range
constexpr std::size_t kMaxPoints = 100000;

std::string text(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

// Position of a key in the schema, or -1 if it cannot be swept.
int schema_position(const std::string& key) {
  const std::vector<std::string> keys = sweepable_keys();
  const auto it = std::find(keys.begin(), keys.end(), key);
  return it == keys.end() ? -1 : static_cast<int>(it - keys.begin());
}

// The table entry of a sweepable "section.key" (schema_position() >= 0).
KeySpec key_spec(const std::string& key) {
  const auto dot = key.find('.');
  for (const Section<ModelConfig>& section : model_sections())
    if (section.name() == key.substr(0, dot)) {
      const SectionSpec spec = section.spec();  // built on each call: keep it while its entry is read
      if (const KeySpec* k = spec.find(key.substr(dot + 1))) return *k;
    }
  throw std::logic_error("no table entry for sweep key " + key);
}

// A text axis: each value read by the key's own reader (choices and message from the table).
void parse_labels(const std::string& key, const YAML::Node& v, SweepAxis& axis, std::vector<std::string>& errors) {
  const std::string path = "monte_carlo.sweep." + key;
  if (!v.IsSequence() || v.size() == 0) {
    errors.push_back(path + " = " + detail::show(v) + " must be a non-empty list of values; allowed " +
                     key_spec(key).expected());
    return;
  }
  const KeySpec spec = key_spec(key);
  for (std::size_t i = 0; i < v.size(); ++i) {
    YAML::Node one;
    one[spec.name] = v[i];
    SectionReader reader(one, "monte_carlo.sweep." + key.substr(0, key.find('.')) + ".", errors);
    if (const auto value = reader.read(spec)) {
      if (std::find(axis.labels.begin(), axis.labels.end(), value->text) != axis.labels.end()) {
        errors.push_back(path + " repeats " + value->text + " (the values of an axis must differ)");
        return;
      }
      axis.values.push_back(static_cast<double>(axis.labels.size()));
      axis.labels.push_back(value->text);
    }
  }
}

bool is_range(const YAML::Node& v) {
  return v.IsMap() && (v["from"] || v["to"] || v["count"] || v["scale"]);
}

void parse_values(const std::string& key, const YAML::Node& v, std::vector<SweepAxis>& axes,
                  std::vector<std::string>& errors) {
  const std::string path = "monte_carlo.sweep." + key;
  if (schema_position(key) < 0) {
    std::string valid;
    for (const std::string& k : sweepable_keys()) valid += (valid.empty() ? "" : ", ") + k;
    errors.push_back(path + " is not a key that can be swept" +
                     (key.rfind("run.", 0) == 0 ? std::string(" (run.* is common to every point: one grid, T and seed)")
                                                : std::string(" (a typo?)")) +
                     "; allowed keys: " + valid);
    return;
  }
  for (const SweepAxis& a : axes)
    if (a.key == key) {
      errors.push_back(path + " is given twice");
      return;
    }
  SweepAxis axis;
  axis.key = key;
  const std::size_t before = errors.size();
  if (key_spec(key).kind == KeyKind::Text) {
    parse_labels(key, v, axis, errors);
    if (errors.size() == before) axes.push_back(std::move(axis));
    return;
  }
  if (v.IsSequence()) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      double x;
      if (!detail::as_number(v[i], x) || !std::isfinite(x)) {
        errors.push_back(path + "[" + std::to_string(i) + "] = " + detail::show(v[i]) + " is not a finite number");
        continue;
      }
      axis.values.push_back(x);
    }
    if (v.size() == 0) errors.push_back(path + " = [] is empty; give at least one value");
  } else if (is_range(v)) {
    double from = 0, to = 0, count = 0;
    bool log_scale = false;
    for (const auto& kv : v) {
      const std::string k = kv.first.as<std::string>();
      if (k != "from" && k != "to" && k != "count" && k != "scale")
        errors.push_back(path + "." + k + " is not a key of a range; allowed from, to, count, scale");
    }
    const auto number = [&](const char* k, double& out) {
      if (!detail::as_number(v[k], out) || !std::isfinite(out)) {
        errors.push_back(path + "." + k + " = " + (v[k] ? detail::show(v[k]) : std::string("(missing)")) +
                         " must be a finite number");
        return false;
      }
      return true;
    };
    const bool ok_from = number("from", from), ok_to = number("to", to), ok_count = number("count", count);
    if (ok_count && (count != std::floor(count) || count < 1 || count > kMaxCount)) {
      errors.push_back(path + ".count = " + text(count) + " is out of range; allowed [1, " + std::to_string(kMaxCount) +
                       "] (integer)");
    }
    if (v["scale"]) {
      const std::string scale = v["scale"].IsScalar() ? v["scale"].Scalar() : detail::show(v["scale"]);
      if (scale == "log") log_scale = true;
      else if (scale != "linear") errors.push_back(path + ".scale = " + scale + " is not linear or log");
    }
    if (log_scale && ok_from && ok_to && !(from > 0 && to > 0))
      errors.push_back(path + " = {from: " + text(from) + ", to: " + text(to) +
                       ", scale: log} needs from > 0 and to > 0");
    if (errors.size() == before) axis.values = range_values(from, to, static_cast<int>(count), log_scale);
  } else {
    errors.push_back(path + " = " + detail::show(v) +
                     " has the wrong type: expected a list of values or a range {from, to, count[, scale: log]}");
  }
  if (errors.size() != before) return;
  std::set<double> seen;
  for (double x : axis.values)
    if (!seen.insert(x).second) {
      errors.push_back(path + " repeats " + text(x) + " (the values of an axis must differ)");
      return;
    }
  axes.push_back(std::move(axis));
}

}  // namespace

std::vector<std::string> sweepable_keys() {
  std::vector<std::string> keys;
  for (const Section<ModelConfig>& section : model_sections())
    if (section.name() == "gear_pair" || section.name() == "load")
      for (const KeySpec& k : section.spec().keys)
        if (k.kind == KeyKind::Real || k.kind == KeyKind::Integer || (k.kind == KeyKind::Text && !k.choices.empty()))
          keys.push_back(section.name() + "." + k.name);
  return keys;
}

std::vector<double> range_values(double from, double to, int count, bool log_scale) {
  std::vector<double> v;
  if (count == 1) return {from};
  for (int i = 0; i < count; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(count - 1);
    double x = log_scale ? std::exp(std::log(from) + f * (std::log(to) - std::log(from))) : from + f * (to - from);
    if (i == 0) x = from;
    if (i == count - 1) x = to;
    v.push_back(x);
  }
  return v;
}

std::vector<SweepAxis> parse_sweep(const YAML::Node& sweep, std::vector<std::string>& errors) {
  std::vector<SweepAxis> axes;
  if (!sweep || sweep.IsNull()) return axes;
  if (!sweep.IsMap()) {
    errors.push_back("monte_carlo.sweep = " + detail::show(sweep) +
                     " must be a map from model keys (e.g. load.sigma) to lists or ranges");
    return axes;
  }
  for (const auto& kv : sweep) {
    const std::string key = kv.first.as<std::string>();
    if (key.find('.') == std::string::npos && kv.second.IsMap() && !is_range(kv.second)) {
      for (const auto& inner : kv.second) parse_values(key + "." + inner.first.as<std::string>(), inner.second, axes, errors);
    } else {
      parse_values(key, kv.second, axes, errors);
    }
  }
  std::stable_sort(axes.begin(), axes.end(),
                   [](const SweepAxis& a, const SweepAxis& b) { return schema_position(a.key) < schema_position(b.key); });
  return axes;
}

std::vector<std::string> Study::keys() const {
  std::vector<std::string> k;
  for (const SweepAxis& a : axes) k.push_back(a.key);
  return k;
}

std::string SweepAxis::value_text(double value, int digits) const {
  if (text()) return labels.at(static_cast<std::size_t>(value));
  std::ostringstream s;
  s.precision(digits);
  s << value;
  return s.str();
}

std::string point_text(const std::vector<SweepAxis>& axes, const std::vector<double>& values) {
  std::string s;
  for (std::size_t i = 0; i < axes.size() && i < values.size(); ++i)
    s += (i ? ", " : "") + axes[i].key + " = " + axes[i].value_text(values[i]);
  return s;
}

std::string point_text(const std::vector<std::string>& keys, const std::vector<double>& values) {
  std::vector<SweepAxis> axes;
  for (const std::string& k : keys) axes.push_back({k, {}, {}});
  return point_text(axes, values);
}

std::string column_name(const std::string& key) { return key == kFrictionKey ? "mu" : key; }

ModelConfig apply_point(const ModelConfig& base, const std::vector<std::string>& keys,
                        const std::vector<double>& values) {
  std::vector<SweepAxis> axes;
  for (const std::string& k : keys) axes.push_back({k, {}, {}});
  return apply_point(base, axes, values);
}

ModelConfig apply_point(const ModelConfig& base, const std::vector<SweepAxis>& axes,
                        const std::vector<double>& values) {
  YAML::Node root = to_yaml(base);
  if (base.run.snapshot_times.empty()) root["run"]["snapshot_times"] = YAML::Node(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const std::string& key = axes[i].key;
    const auto dot = key.find('.');
    const double v = values.at(i);
    YAML::Node node(v);
    if (axes[i].text()) {
      node = YAML::Node(axes[i].value_text(v));
    } else if (v == std::floor(v) && std::abs(v) < 9007199254740992.0) {
      for (const Section<ModelConfig>& section : model_sections())
        for (const KeySpec& k : section.spec().keys)
          if (k.kind == KeyKind::Integer && section.name() + "." + k.name == key)
            node = YAML::Node(static_cast<long long>(v));
    }
    root[key.substr(0, dot)][key.substr(dot + 1)] = node;
  }
  return parse_config(root);
}

Study make_study(const ModelConfig& base, const std::vector<double>& mu, const std::vector<SweepAxis>& sweep) {
  Study study;
  study.base = base;
  study.axes.push_back({kFrictionKey, mu, {}});
  for (const SweepAxis& a : sweep) {
    if (a.key == kFrictionKey) study.axes.front().values = a.values;
    else study.axes.push_back(a);
  }
  std::size_t total = 1;
  for (const SweepAxis& a : study.axes) {
    if (a.values.empty()) throw ConfigError("invalid configuration:\n  monte_carlo.sweep." + a.key + " has no values");
    total *= a.values.size();
    if (total > kMaxPoints)
      throw ConfigError("invalid configuration:\n  monte_carlo.sweep has more than " + std::to_string(kMaxPoints) +
                        " points; allowed at most that many");
  }
  const std::vector<std::string> keys = study.keys();
  std::vector<std::string> errors;
  std::size_t bad = 0;
  std::map<std::string, std::size_t> schedules;
  for (std::size_t p = 0; p < total; ++p) {
    StudyPoint point;
    point.index = p;
    std::size_t rest = p;
    point.values.resize(study.axes.size());
    for (std::size_t a = study.axes.size(); a-- > 0;) {
      point.values[a] = study.axes[a].values[rest % study.axes[a].values.size()];
      rest /= study.axes[a].values.size();
    }
    const std::string where = "monte_carlo.sweep: point " + std::to_string(p) + " (" + point_text(study.axes, point.values) + ")";
    // The mesh must stay resolved by the grid: a step may not span a stiffness interval.
    std::string speed_problem;
    for (std::size_t a = 0; a < keys.size(); ++a) {
      if (keys[a] != "gear_pair.pinion_speed") continue;
      try {
        std::vector<double> still = point.values;
        still[a] = 0.0;  // the geometry without this check; other errors come from apply_point below
        const ModelConfig geometry = apply_point(base, study.axes, still);
        const GearPair g = derive(geometry.gear);
        const double shortest = std::min(g.single_pair_angle, g.mesh_period_angle - g.single_pair_angle);
        const double h = base.run.time_step, w = point.values[a];
        if (w * h >= shortest)
          speed_problem = where + ": gear_pair.pinion_speed = " + text(w) + " rad/s is out of range at run.time_step = " +
                          text(h) + " s (a step would span a whole stiffness interval, so h no longer resolves the mesh); "
                          "allowed [0, " + text(shortest / h) + ") rad/s";
      } catch (const ConfigError&) {
      }
    }
    try {
      if (!speed_problem.empty()) throw ConfigError(speed_problem);
      point.config = apply_point(base, study.axes, point.values);
    } catch (const ConfigError& e) {
      if (++bad <= 10) {
        std::string why = e.what();
        const std::string prefix = "invalid configuration:\n  ";
        if (why.rfind(prefix, 0) == 0) why = why.substr(prefix.size());
        if (!speed_problem.empty()) errors.push_back(why);
        else errors.push_back(where + " is refused: " + why);
      }
      continue;
    }
    ModelConfig shared = point.config;  // what lanes of one Ensemble must share
    shared.friction_coefficient = 0;
    shared.gear.mesh_phase = 0;
    shared.load = LoadSettings{};
    YAML::Emitter e;
    e << to_yaml(shared);
    point.schedule = schedules.emplace(e.c_str(), schedules.size()).first->second;
    study.points.push_back(std::move(point));
  }
  if (bad > 10) errors.push_back("... and " + std::to_string(bad - 10) + " more bad points");
  detail::throw_if_errors(errors);
  return study;
}

void read_sweep(const YAML::Node& section, std::vector<double>& mu, std::vector<SweepAxis>& sweep,
                std::vector<std::string>& errors) {
  sweep = parse_sweep(section["sweep"], errors);
  for (auto it = sweep.begin(); it != sweep.end(); ++it) {
    if (it->key != kFrictionKey) continue;
    mu = it->values;  // the sweep's friction axis replaces monte_carlo.mu
    sweep.erase(it);
    std::set<std::string> names;
    for (double m : mu) {
      if (m < 0 || m > kMaxFrictionCoefficient)
        errors.push_back("monte_carlo.sweep.gear_pair.friction_coefficient: " + text(m) + " is out of range; allowed [0, " +
                         text(kMaxFrictionCoefficient) + "] -");
      else if (!names.insert(mu_label(m)).second)
        errors.push_back("monte_carlo.sweep.gear_pair.friction_coefficient repeats " + text(m) +
                         " in the 4th decimal (values must differ there: they name the runs)");
    }
    break;
  }
}

SweepAxis parse_sweep_argument(const std::string& arg) {
  const auto eq = arg.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError("--sweep expects SECTION.KEY=v1,v2,... or SECTION.KEY=from:to:count[:log], got '" + arg + "'");
  const std::string key = arg.substr(0, eq), rest = arg.substr(eq + 1);
  YAML::Node sweep;
  if (rest.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream ss(rest);
    for (std::string p; std::getline(ss, p, ':');) parts.push_back(p);
    if (parts.size() != 3 && parts.size() != 4)
      throw ConfigError("--sweep " + arg + ": a range is from:to:count or from:to:count:log");
    sweep[key]["from"] = YAML::Load(parts[0]);
    sweep[key]["to"] = YAML::Load(parts[1]);
    sweep[key]["count"] = YAML::Load(parts[2]);
    if (parts.size() == 4) sweep[key]["scale"] = parts[3];
  } else {
    std::stringstream ss(rest);
    sweep[key] = YAML::Node(YAML::NodeType::Sequence);
    for (std::string p; std::getline(ss, p, ',');) sweep[key].push_back(YAML::Load(p));
  }
  std::vector<std::string> errors;
  const std::vector<SweepAxis> axes = parse_sweep(sweep, errors);
  detail::throw_if_errors(errors);
  return axes.at(0);
}

}  // namespace gear_dynamics
