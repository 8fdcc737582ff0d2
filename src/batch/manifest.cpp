#include "gear_dynamics/batch/manifest.hpp"
#include "gear_dynamics/batch/run_record.hpp"  // same_value

#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>

#include "gear_dynamics/config/sweep.hpp"
#include "gear_dynamics/engine/ensemble.hpp"  // kNumbersGeneration

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Checks a YAML text's syntax without building yaml-cpp's tree (throws YAML::ParserException).
class SyntaxOnly : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

// A manifest's text split into its top-level `runs:` block sequence, one text per item (each
// parsed alone as `runs:` + item), and the rest with `runs:` left empty: yaml-cpp's tree of a
// whole manifest costs kilobytes per run (bench/README.md §8). False if the
// text has no such block (then it is parsed whole).
bool split_runs(const std::string& text, std::string& rest, std::vector<std::string>& items) {
  std::istringstream in(text);
  std::string line;
  std::size_t indent = std::string::npos;  // of the items' "-"
  bool inside = false, found = false;
  while (std::getline(in, line)) {
    if (!inside && line.rfind("runs:", 0) == 0 && line.find_first_not_of(' ', 5) == std::string::npos) {
      inside = found = true;
      rest += line + '\n';
      continue;
    }
    if (inside) {
      const std::size_t first = line.find_first_not_of(' ');
      if (first == std::string::npos || line[first] == '#') {  // blank or comment: to the item in hand
        if (!items.empty()) items.back() += line + '\n';
        continue;
      }
      const bool dash = line[first] == '-' && (first + 1 == line.size() || line[first + 1] == ' ');
      if (indent == std::string::npos) {
        if (!dash) return false;  // not a block sequence
        indent = first;
      }
      if (first > indent || (first == indent && dash)) {  // an item's line, or a new item
        if (first == indent && dash) items.emplace_back();
        items.back() += line + '\n';
        continue;
      }
      inside = false;  // the next top-level key
    }
    rest += line + '\n';
  }
  return found && indent != std::string::npos;
}

using Fail = std::function<void(const std::string&)>;

// `key` of the map `n` as a T, or a failure naming `where` + key and the value.
template <class T>
T field(const YAML::Node& n, const std::string& key, const std::string& where, const Fail& fail) {
  const YAML::Node v = n[key];
  if (!v) fail(where + key + " is missing");
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    YAML::Emitter e;
    e << YAML::Flow << v;
    fail(where + key + " = '" + e.c_str() + "' is not of the expected type");
  }
  return T{};
}

// The manifest's YAML tree without its runs (`items`: the runs' texts, if they could be split off).
YAML::Node load_manifest(const std::string& path, std::vector<std::string>& items) {
  std::ifstream file(path);
  if (!file) throw YAML::BadFile(path);
  std::ostringstream text;
  text << file.rdbuf();
  std::istringstream syntax(text.str());
  YAML::Parser parser(syntax);
  SyntaxOnly ignore;
  parser.HandleNextDocument(ignore);  // the whole text's syntax errors first, as one tree's
  std::string rest;
  return YAML::Load(split_runs(text.str(), rest, items) ? rest : text.str());
}

void read_grid(const YAML::Node& root, Manifest& m, const Fail& fail) {
  m.axes = field<std::vector<std::string>>(root, "axes", "", fail);
  if (m.axes.empty() || m.axes.front() != kFrictionKey) fail("axes must start with " + std::string(kFrictionKey));
  if (root["axis_labels"])
    m.axis_labels = field<std::map<std::string, std::vector<std::string>>>(root, "axis_labels", "", fail);
  const YAML::Node points = root["points"];
  if (!points || !points.IsSequence()) fail("points must be a list");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string at = "points[" + std::to_string(i) + "].";
    if (field<std::size_t>(points[i], "point", at, fail) != i) fail(at + "point must be " + std::to_string(i));
    const auto values = field<std::vector<double>>(points[i], "values", at, fail);
    if (values.size() != m.axes.size()) fail("points[" + std::to_string(i) + "] needs one value per axis");
    m.points.push_back(values);
  }
}

ManifestRun read_run(const YAML::Node& r, std::size_t i, const Manifest& m, const Fail& fail) {
  const std::string at = "runs[" + std::to_string(i) + "].";
  ManifestRun e;
  e.name = field<std::string>(r, "name", at, fail);
  e.file = field<std::string>(r, "file", at, fail);
  e.mu = field<double>(r, "mu", at, fail);
  e.realization = field<std::uint32_t>(r, "realization", at, fail);
  if (m.study) {
    e.point = field<std::size_t>(r, "point", at, fail);
    if (e.point >= m.points.size()) fail("runs[" + std::to_string(i) + "].point is not among the points");
    if (!same_value(m.points[e.point][0], e.mu)) fail("runs[" + std::to_string(i) + "].mu differs from its point's");
  }
  const std::string kind_text = field<std::string>(r, "kind", at, fail);
  const auto kind = run_kind_from(kind_text);
  if (!kind) fail(at + "kind = '" + kind_text + "' is not S1, phase or stochastic");
  e.kind = *kind;
  if (e.file.empty() || fs::path(e.file).filename() != e.file)
    fail("runs[" + std::to_string(i) + "].file = '" + e.file + "' must be a file name inside the folder");
  return e;
}

}  // namespace

std::string manifest_file_name(int shard_index, int shard_count) {
  if (shard_count == 1) return "manifest.yaml";
  return "manifest_shard" + std::to_string(shard_index) + "of" + std::to_string(shard_count) + ".yaml";
}

bool is_manifest_file(const std::string& file) { return file.rfind("manifest", 0) == 0 && ends_with(file, ".yaml"); }

std::string bag_file_name(const std::string& run_name) { return run_name + ".bag"; }

std::string active_file_name(const std::string& run_name) { return run_name + ".bag.active"; }

bool is_bag_file(const std::string& file) { return ends_with(file, ".bag"); }

bool is_active_file(const std::string& file) { return ends_with(file, ".bag.active"); }

bool is_temporary_file(const std::string& file) { return ends_with(file, ".tmp"); }

YAML::Node manifest_config(const ModelConfig& model, const BatchSettings& settings) {
  YAML::Node n = to_yaml(model);
  n["monte_carlo"] = content_yaml(settings);
  for (const SweepAxis& a : settings.sweep) {  // only a study has it: a mu sweep's config has no sweep key
    YAML::Node values;
    for (double v : a.values) values.push_back(v);
    values.SetStyle(YAML::EmitterStyle::Flow);
    n["monte_carlo"]["sweep"][a.key] = values;
  }
  return n;
}

const char* package_version() { return GEAR_DYNAMICS_VERSION; }

std::string manifest_text(const Manifest& m) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << m.format();
  out << YAML::Key << "package_version" << YAML::Value << m.package_version;
  if (!m.instruction_set.empty()) out << YAML::Key << "instruction_set" << YAML::Value << m.instruction_set;
  out << YAML::Key << "numbers" << YAML::Value << m.numbers;
  out << YAML::Key << "complete" << YAML::Value << m.complete;
  out << YAML::Key << "config" << YAML::Value << m.config;
  out << YAML::Key << "shard_index" << YAML::Value << m.shard_index;
  out << YAML::Key << "shard_count" << YAML::Value << m.shard_count;
  if (m.study) {  // format 2: the grid, one entry per point with its value on every axis
    out << YAML::Key << "axes" << YAML::Value << YAML::Flow << m.axes;
    if (!m.axis_labels.empty()) out << YAML::Key << "axis_labels" << YAML::Value << YAML::Flow << m.axis_labels;
    out << YAML::Key << "points" << YAML::Value << YAML::BeginSeq;
    for (std::size_t i = 0; i < m.points.size(); ++i)
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "point" << YAML::Value << i << YAML::Key << "values"
          << YAML::Value << YAML::Flow << m.points[i] << YAML::EndMap;
    out << YAML::EndSeq;
  }
  out << YAML::Key << "runs" << YAML::Value << YAML::BeginSeq;
  for (const ManifestRun& r : m.runs) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << r.name << YAML::Key << "kind"
        << YAML::Value << to_string(r.kind) << YAML::Key << "mu" << YAML::Value << r.mu << YAML::Key << "realization"
        << YAML::Value << r.realization;
    if (m.study) out << YAML::Key << "point" << YAML::Value << r.point;
    out << YAML::Key << "file" << YAML::Value << r.file << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void write_manifest_file(const std::string& folder, const Manifest& manifest) {
  const fs::path dir(folder), final_path = dir / manifest_file_name(manifest.shard_index, manifest.shard_count);
  const fs::path tmp = dir / (final_path.filename().string() + ".tmp");
  {
    std::ofstream f(tmp);
    f << manifest_text(manifest);
    f.close();
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, final_path);
}

Manifest read_manifest(const std::string& path) {
  const Fail fail = [&](const std::string& why) {
    throw ManifestError("manifest " + path + ": " + why);
  };
  Manifest m;
  YAML::Node root;
  std::vector<std::string> items;  // the runs, if split_runs could split them off
  try {
    root = load_manifest(path, items);
  } catch (const YAML::Exception& ex) {
    fail(std::string("not readable as YAML: ") + ex.what());
  }
  try {
    if (!root.IsMap()) fail("not a YAML map");
    const std::string format = root["format"] ? root["format"].as<std::string>() : "(missing)";
    if (format != kManifestFormat && format != kManifestFormatStudy)
      fail("format is '" + format + "', expected '" + kManifestFormat + "' or '" + kManifestFormatStudy + "'");
    m.study = format == kManifestFormatStudy;
    m.package_version = root["package_version"] ? field<std::string>(root, "package_version", "", fail) : "";
    m.instruction_set = root["instruction_set"] ? field<std::string>(root, "instruction_set", "", fail) : "";
    m.numbers = root["numbers"] ? field<int>(root, "numbers", "", fail) : 1;  // a manifest without it predates it
    m.complete = root["complete"] && field<bool>(root, "complete", "", fail);
    m.config = root["config"];
    if (!m.config || !m.config.IsMap()) fail("config must be a map");
    if (m.study) read_grid(root, m, fail);
    m.shard_index = field<int>(root, "shard_index", "", fail);
    m.shard_count = field<int>(root, "shard_count", "", fail);
    if (m.shard_count < 1 || m.shard_index < 0 || m.shard_index >= m.shard_count)
      fail("shard_index = " + std::to_string(m.shard_index) + " is out of range for shard_count = " +
           std::to_string(m.shard_count));
    const YAML::Node runs = root["runs"];
    if (!runs || !(runs.IsSequence() || runs.IsNull())) fail("runs must be a list");
    const std::size_t count = items.empty() ? (runs.IsSequence() ? runs.size() : 0) : items.size();
    for (std::size_t i = 0; i < count; ++i)
      m.runs.push_back(read_run(items.empty() ? runs[i] : YAML::Load("runs:\n" + items[i])["runs"][0], i, m, fail));
  } catch (const YAML::Exception& ex) {
    fail(std::string("missing or mistyped field: ") + ex.what());
  }
  return m;
}

ModelConfig manifest_model(const Manifest& manifest, const std::string& path) {
  try {
    return parse_config(manifest.config);
  } catch (const ConfigError& ex) {
    throw ManifestError("manifest " + path + ": its config is not a valid model configuration: " + ex.what());
  }
}

std::vector<std::string> manifests_in(const std::string& folder) {
  std::vector<std::string> out;
  for (const auto& f : fs::directory_iterator(folder)) {
    const std::string name = f.path().filename().string();
    if (f.is_regular_file() && name.rfind("manifest", 0) == 0 && f.path().extension() == ".yaml")
      out.push_back(f.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace gear_dynamics
