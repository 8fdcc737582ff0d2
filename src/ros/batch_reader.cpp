#include "gear_dynamics/ros/batch_reader.hpp"

#include <ros/console.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/RunSummary.h"

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

struct ManifestRun {
  std::string name, file;
  RunKind kind = RunKind::Stochastic;
  double mu = 0;
  std::uint32_t realization = 0;
};

struct Manifest {
  fs::path path;
  ModelConfig config;
  std::string config_key;
  int shard_index = 0, shard_count = 1;
  std::vector<ManifestRun> runs;
};

// Why a bag is not used.
struct Skip : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The model configuration as text, without what legitimately differs between the runs of one
// batch (mu and the initial mesh phase are per run).
std::string config_key(ModelConfig c) {
  c.friction_coefficient = 0;
  c.gear.mesh_phase = 0;
  YAML::Emitter e;
  e << to_yaml(c);
  return e.c_str();
}

// The first line where two configuration texts differ, for the message.
std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb, section;
  while (true) {
    const bool ga = static_cast<bool>(std::getline(sa, la)), gb = static_cast<bool>(std::getline(sb, lb));
    if (!ga && !gb) return "";
    if (!ga || !gb || la != lb) return section + "'" + lb + "' here vs '" + la + "'";
    if (!la.empty() && la[0] != ' ') section = la;  // "run:" etc.
  }
}

bool same(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }

Manifest parse_manifest(const fs::path& path) {
  const auto fail = [&](const std::string& why) -> void { throw BatchReadError("manifest " + path.string() + ": " + why); };
  Manifest m;
  m.path = path;
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::Exception& ex) {
    fail(std::string("not readable as YAML: ") + ex.what());
  }
  try {
    if (!root.IsMap()) fail("not a YAML map");
    const std::string format = root["format"] ? root["format"].as<std::string>() : "(missing)";
    if (format != kManifestFormat) fail("format is '" + format + "', expected '" + kManifestFormat + "'");
    try {
      m.config = parse_config(root["config"]);
    } catch (const ConfigError& ex) {
      fail(std::string("its config is not a valid model configuration: ") + ex.what());
    }
    m.config_key = config_key(m.config);
    m.shard_index = root["shard_index"].as<int>();
    m.shard_count = root["shard_count"].as<int>();
    if (m.shard_count < 1 || m.shard_index < 0 || m.shard_index >= m.shard_count)
      fail("shard_index = " + std::to_string(m.shard_index) + " is out of range for shard_count = " +
           std::to_string(m.shard_count));
    const YAML::Node runs = root["runs"];
    if (!runs || !(runs.IsSequence() || runs.IsNull())) fail("runs must be a list");
    for (std::size_t i = 0; runs.IsSequence() && i < runs.size(); ++i) {
      const YAML::Node r = runs[i];
      ManifestRun e;
      e.name = r["name"].as<std::string>();
      e.file = r["file"].as<std::string>();
      e.mu = r["mu"].as<double>();
      e.realization = r["realization"].as<std::uint32_t>();
      const auto kind = run_kind_from(r["kind"].as<std::string>());
      if (!kind) fail("runs[" + std::to_string(i) + "].kind = '" + r["kind"].as<std::string>() + "' is not S1, phase or stochastic");
      e.kind = *kind;
      if (e.file.empty() || fs::path(e.file).filename() != e.file)
        fail("runs[" + std::to_string(i) + "].file = '" + e.file + "' must be a file name inside the folder");
      m.runs.push_back(e);
    }
  } catch (const YAML::Exception& ex) {
    fail(std::string("missing or mistyped field: ") + ex.what());
  }
  return m;
}

std::vector<fs::path> manifests_in(const fs::path& folder) {
  std::vector<fs::path> out;
  for (const auto& f : fs::directory_iterator(folder)) {
    const std::string name = f.path().filename().string();
    if (f.is_regular_file() && name.rfind("manifest", 0) == 0 && f.path().extension() == ".yaml") out.push_back(f.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// Reads one bag; `series` (if not null) receives its GearState rows in the paper's units.
RunRecord read_run(const fs::path& path, const ManifestRun& e, const Manifest& manifest, std::string* series) {
  const auto require = [](bool ok, const std::string& why) {
    if (!ok) throw Skip(why);
  };
  rosbag::Bag bag(path.string(), rosbag::bagmode::Read);
  std::vector<std::string> topics{kRunInfoTopic, kSummaryTopic};
  if (series) topics.emplace_back(kStateTopic);
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  RunInfo::ConstPtr info;
  RunSummary::ConstPtr summary;
  int infos = 0, summaries = 0;
  std::ostringstream rows;
  rows.precision(10);
  for (const rosbag::MessageInstance& m : view) {
    const std::string& topic = m.getTopic();
    if (topic == kRunInfoTopic) {
      ++infos;
      info = m.instantiate<RunInfo>();
      require(info != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/RunInfo");
    } else if (topic == kSummaryTopic) {
      ++summaries;
      summary = m.instantiate<RunSummary>();
      require(summary != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/RunSummary");
    } else {
      const GearState::ConstPtr s = m.instantiate<GearState>();
      require(s != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/GearState");
      rows << e.name << ',' << to_string(e.kind) << ',' << e.mu << ',' << e.realization << ',' << s->t << ','
           << s->delta * kToPaperUnits << ',' << s->delta_dot * kToPaperUnits << ',' << s->phi * kToPaperUnits << '\n';
    }
  }
  require(infos == 1, "has " + std::to_string(infos) + " " + kRunInfoTopic + " messages, expected 1");
  require(summaries == 1, summaries == 0 ? std::string("has no ") + kSummaryTopic + " (the run did not finish)"
                                         : "has " + std::to_string(summaries) + " " + kSummaryTopic + " messages, expected 1");

  // Is it this run of this batch?
  const ModelConfig& c = manifest.config;
  require(info->kind == to_string(e.kind) && info->realization == e.realization && same(info->mu, e.mu),
          "run_info is run (" + info->kind + ", realization " + std::to_string(info->realization) + ", mu " +
              std::to_string(info->mu) + "), the manifest lists (" + to_string(e.kind) + ", " +
              std::to_string(e.realization) + ", " + std::to_string(e.mu) + ") (a bag of another batch)");
  require(info->seed == c.seed, "run_info seed " + std::to_string(info->seed) + " differs from the batch's " +
                                    std::to_string(c.seed) + " (a bag of another batch)");
  std::string key;
  try {
    key = config_key(parse_config(YAML::Load(info->parameters_yaml)));
  } catch (const std::exception& ex) {
    throw Skip(std::string("run_info parameters_yaml is not a valid configuration: ") + ex.what());
  }
  require(key == manifest.config_key, "run_info configuration differs from the manifest's at " +
                                          first_difference(manifest.config_key, key) + " (a bag of another batch)");
  require(same(info->time_step, c.run.time_step) && same(info->duration, c.run.duration),
          "run_info time_step/duration differ from the manifest's (a bag of another batch)");
  require(summary->run_name == e.name && summary->kind == to_string(e.kind) && summary->realization == e.realization &&
              same(summary->mu, e.mu),
          "summary is of run '" + summary->run_name + "', not '" + e.name + "'");
  require(summary->snapshot_delta.size() == summary->snapshot_times.size() &&
              summary->snapshot_delta_dot.size() == summary->snapshot_times.size(),
          "summary snapshot arrays differ in length");
  require(all_finite({summary->center_distance, summary->steady_state_time, summary->steady_state_time_fine,
                      summary->final_delta, summary->final_delta_dot, summary->final_phi}) &&
              all_finite(summary->snapshot_times) && all_finite(summary->snapshot_delta) &&
              all_finite(summary->snapshot_delta_dot),
          "summary holds a non-finite value");

  RunRecord r;
  r.name = e.name;
  r.kind = e.kind;
  r.mu = e.mu;
  r.index = e.realization;
  r.center_distance = summary->center_distance;
  r.steady_state_time = summary->steady_state_time;
  r.steady_state_time_fine = summary->steady_state_time_fine;
  r.reached_steady_state = summary->reached_steady_state;
  r.final_delta = summary->final_delta;
  r.final_delta_dot = summary->final_delta_dot;
  r.final_phi = summary->final_phi;
  r.snapshot_times = summary->snapshot_times;
  r.snapshot_delta = summary->snapshot_delta;
  r.snapshot_delta_dot = summary->snapshot_delta_dot;
  if (series) *series = rows.str();
  return r;
}

}  // namespace

BatchInputs read_batches(const std::vector<std::string>& folder_args, const ReadOptions& options) {
  BatchInputs in;
  // The folders, each once.
  std::vector<fs::path> folders;
  for (const std::string& f : folder_args) {
    std::error_code ec;
    if (!fs::is_directory(f, ec)) throw BatchReadError("batch folder '" + f + "' does not exist or is not a folder");
    const fs::path canonical = fs::canonical(f);
    if (std::find(folders.begin(), folders.end(), canonical) == folders.end()) folders.push_back(canonical);
  }
  if (folders.empty()) throw BatchReadError("no batch folder given");
  for (const auto& f : folders) in.folders.push_back(f.string());

  // Manifests: one batch (one model configuration), runs listed by name.
  std::vector<Manifest> manifests;
  std::map<std::string, std::pair<ManifestRun, const Manifest*>> listed;
  std::map<int, std::set<int>> shards;  // shard_count -> indices seen
  for (const fs::path& folder : folders) {
    const auto paths = manifests_in(folder);
    if (paths.empty())
      throw BatchReadError("batch folder '" + folder.string() + "' has no manifest.yaml (not a batch folder, or the batch has not started)");
    for (const fs::path& p : paths) manifests.push_back(parse_manifest(p));
  }
  for (const Manifest& m : manifests) {
    if (m.config_key != manifests.front().config_key)
      throw BatchReadError("manifests " + manifests.front().path.string() + " and " + m.path.string() +
                           " belong to different batches: their configurations differ at " +
                           first_difference(manifests.front().config_key, m.config_key));
    shards[m.shard_count].insert(m.shard_index);
    for (const ManifestRun& e : m.runs) {
      const auto [it, inserted] = listed.emplace(e.name, std::make_pair(e, &m));
      const ManifestRun& had = it->second.first;
      if (!inserted && (had.kind != e.kind || had.realization != e.realization || !same(had.mu, e.mu)))
        throw BatchReadError("run " + e.name + " is listed differently in " + it->second.second->path.string() +
                             " and " + m.path.string());
    }
  }
  in.config = manifests.front().config;
  in.expected_runs = listed.size();
  for (const auto& [count, seen] : shards)
    for (int i = 0; i < count; ++i)
      if (!seen.count(i)) {
        in.missing.push_back("shard " + std::to_string(i) + " of " + std::to_string(count) + " (no manifest found)");
        ROS_WARN("batch: shard %d of %d has no manifest in the folders given; its runs are not counted", i, count);
      }

  const auto skip = [&](const fs::path& file, const std::string& reason) {
    ROS_WARN("batch: skipping %s: %s", file.c_str(), reason.c_str());
    in.skipped.push_back({file.string(), reason});
  };

  // Files no manifest accounts for.
  std::set<fs::path> referenced;
  for (const auto& [name, entry] : listed)
    for (const fs::path& folder : folders) referenced.insert(folder / entry.first.file);
  for (const fs::path& folder : folders)
    for (const auto& f : fs::directory_iterator(folder)) {
      const std::string name = f.path().filename().string();
      const auto ends = [&](const std::string& suffix) {
        return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
      };
      if (ends(".bag.active")) skip(f.path(), "unfinished (.active): the run was in flight or abandoned");
      else if (ends(".bag") && !referenced.count(f.path())) skip(f.path(), "not listed in any manifest of the batch");
    }

  std::ofstream series;
  if (!options.series_csv.empty()) {
    series.open(options.series_csv);
    if (!series) throw BatchReadError("cannot write " + options.series_csv);
    series << "run,kind,mu,index,t[s],delta[mm],delta_dot[mm/s],phi[mm/s^2]\n";
  }
  std::map<fs::path, std::size_t> usable;  // runs each folder provides
  for (const auto& [name, entry] : listed) {
    const ManifestRun& e = entry.first;
    const bool wants_series = series.is_open() && same(e.mu, options.series_mu) &&
                              (e.kind == RunKind::S1 || (e.kind == RunKind::Stochastic && e.realization <= 1));
    std::string used;
    for (const fs::path& folder : folders) {
      const fs::path file = folder / e.file;
      if (!fs::exists(file)) continue;
      if (!used.empty()) {  // the folder still contributes this run
        skip(file, "duplicate of " + used + " (not read)");
        ++usable[folder];
        continue;
      }
      std::string rows;
      try {
        in.runs.push_back(read_run(file, e, *entry.second, wants_series ? &rows : nullptr));
        used = file.string();
        ++usable[folder];
        series << rows;
      } catch (const Skip& ex) {
        skip(file, ex.what());
      } catch (const rosbag::BagException& ex) {
        skip(file, std::string("unreadable bag (truncated or corrupted): ") + ex.what());
      } catch (const std::exception& ex) {  // e.g. ros::serialization errors in a damaged chunk
        skip(file, std::string("unreadable bag: ") + ex.what());
      }
    }
    if (used.empty()) {
      ROS_WARN("batch: run %s has no usable bag", name.c_str());
      in.missing.push_back(name);
    }
  }
  if (series.is_open()) {
    series.close();
    if (!series) throw BatchReadError("error writing " + options.series_csv);
  }
  for (const fs::path& folder : folders)
    if (!usable[folder])
      throw BatchReadError("batch folder '" + folder.string() + "' has no usable bag (" +
                           std::to_string(in.skipped.size()) + " skipped, " + std::to_string(in.missing.size()) +
                           " runs missing)");
  ROS_INFO("batch: %zu of %zu runs read from %zu folder(s); %zu bags skipped, %zu missing (runs or shards)", in.runs.size(),
           in.expected_runs, folders.size(), in.skipped.size(), in.missing.size());
  return in;
}

bool batch_complete(const std::string& folder) {
  try {
    const auto paths = manifests_in(folder);
    if (paths.empty()) return false;
    for (const fs::path& p : paths)
      for (const ManifestRun& e : parse_manifest(p).runs)
        if (!fs::exists(fs::path(folder) / e.file)) return false;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace gear_dynamics
