#include "gear_dynamics/ros/batch_reader.hpp"

#include <fcntl.h>
#include <ros/console.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "gear_dynamics/GearState.h"
#include "gear_dynamics/PoincarePoint.h"
#include "gear_dynamics/RunInfo.h"
#include "gear_dynamics/RunSummary.h"
#include "gear_dynamics/ros/conversions.hpp"  // the topics of a run bag

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

// A manifest of the folders read, with what the reader compares across manifests and bags.
struct FolderManifest : Manifest {
  fs::path path;
  ModelConfig model;                     // its config, parsed
  std::string config_key;                // model as text, mu and phi0 set aside (config_key)
  std::vector<std::string> point_keys;   // format 2: config_key of each point
  std::string grid;                      // format 2: axes and points as text, to compare manifests
  std::string content;                   // config.monte_carlo (what the batch holds) as text
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

// A study manifest's axes with the labels of its text axes (values: filled by the caller).
std::vector<SweepAxis> manifest_axes(const Manifest& m) {
  std::vector<SweepAxis> axes;
  for (const std::string& key : m.axes) {
    const auto labels = m.axis_labels.find(key);
    axes.push_back({key, {}, labels == m.axis_labels.end() ? std::vector<std::string>{} : labels->second});
  }
  return axes;
}

FolderManifest parse_manifest(const fs::path& path) {
  FolderManifest m;
  try {
    static_cast<Manifest&>(m) = read_manifest(path.string());
    m.path = path;
    m.model = manifest_model(m, path.string());
  } catch (const ManifestError& ex) {
    throw BatchReadError(ex.what());
  }
  m.config_key = config_key(m.model);
  if (m.config["monte_carlo"]) {
    YAML::Emitter e;
    e << YAML::Flow << m.config["monte_carlo"];
    m.content = e.c_str();
  }
  if (m.study) {
    for (std::size_t i = 0; i < m.points.size(); ++i) {
      try {
        m.point_keys.push_back(config_key(apply_point(m.model, manifest_axes(m), m.points[i])));
      } catch (const ConfigError& ex) {
        throw BatchReadError("manifest " + path.string() + ": points[" + std::to_string(i) +
                             "] is not a valid configuration: " + ex.what());
      }
    }
    YAML::Emitter e;
    e << YAML::Flow << m.axes << m.axis_labels << m.points;
    m.grid = e.c_str();
  }
  return m;
}

std::vector<fs::path> manifest_paths(const fs::path& folder) {
  std::vector<fs::path> out;
  for (const std::string& p : manifests_in(folder.string())) out.emplace_back(p);
  return out;
}

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// What a run's bag holds, as read by rosbag.
struct BagContents {
  std::uint32_t infos = 0, summaries = 0;
  RunInfo info;
  RunSummary summary;
  RunSeries series;  // every GearState, if asked for (SI)
  std::vector<double> section_t, section_delta, section_delta_dot;  // every PoincarePoint (SI)
  std::vector<BearingSummary> bearings;  // the bearings model's window statistics (one, or none)
};

// Reads one bag (its states only if `states`) with `bag`, a
// closed Bag that is reopened for each file: constructing a rosbag::Bag crawls the ROS packages for
// its encryptor plugin, which costs more than reading a small bag. Throws Skip or rosbag's
// exceptions (the caller then replaces `bag`).
BagContents read_bag(rosbag::Bag& bag, const fs::path& path, bool states) {
  const auto require = [](bool ok, const std::string& why) {
    if (!ok) throw Skip(why);
  };
  bag.open(path.string(), rosbag::bagmode::Read);
  std::vector<std::string> topics{kRunInfoTopic, kSummaryTopic, kPoincareTopic, kBearingSummaryTopic};
  if (states) topics.emplace_back(kStateTopic);
  BagContents c;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topics))) {
    const std::string& topic = m.getTopic();
    if (topic == kRunInfoTopic) {
      ++c.infos;
      const RunInfo::ConstPtr info = m.instantiate<RunInfo>();
      require(info != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/RunInfo");
      c.info = *info;
    } else if (topic == kSummaryTopic) {
      ++c.summaries;
      const RunSummary::ConstPtr summary = m.instantiate<RunSummary>();
      require(summary != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/RunSummary");
      c.summary = *summary;
    } else if (topic == kPoincareTopic) {
      const PoincarePoint::ConstPtr p = m.instantiate<PoincarePoint>();
      require(p != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/PoincarePoint");
      c.section_t.push_back(p->t);
      c.section_delta.push_back(p->delta);
      c.section_delta_dot.push_back(p->delta_dot);
    } else if (topic == kBearingSummaryTopic) {
      const BearingSummary::ConstPtr b = m.instantiate<BearingSummary>();
      require(b != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/BearingSummary");
      c.bearings.push_back(*b);
    } else {
      const GearState::ConstPtr s = m.instantiate<GearState>();
      require(s != nullptr, topic + " holds " + m.getDataType() + ", not gear_dynamics/GearState");
      c.series.t.push_back(s->t);
      c.series.delta.push_back(s->delta);
      c.series.delta_dot.push_back(s->delta_dot);
      c.series.phi.push_back(s->phi);
    }
  }
  bag.close();
  return c;
}

// BagContents through a pipe, in ROS serialization: the fields in order, for any stream (the
// length, writing or reading).
template <class Stream, class Contents>
void fields(Stream& stream, Contents& c) {
  stream.next(c.infos);
  stream.next(c.summaries);
  stream.next(c.info);
  stream.next(c.summary);
  stream.next(c.series.t);
  stream.next(c.series.delta);
  stream.next(c.series.delta_dot);
  stream.next(c.series.phi);
  stream.next(c.section_t);
  stream.next(c.section_delta);
  stream.next(c.section_delta_dot);
  stream.next(c.bearings);
}

std::vector<std::uint8_t> serialize(const BagContents& c) {
  ros::serialization::LStream length;
  fields(length, c);
  std::vector<std::uint8_t> buf(length.getLength());
  ros::serialization::OStream out(buf.data(), length.getLength());
  fields(out, c);
  return buf;
}

BagContents deserialize(std::uint8_t* data, std::uint32_t size) {
  BagContents c;
  ros::serialization::IStream in(data, size);
  fields(in, c);
  return c;
}

bool write_all(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// One bag to read, with its states if `states`.
struct BagJob {
  fs::path file;
  bool states = false;
};

// What came of reading one bag: its contents, or why not.
struct BagRead {
  std::unique_ptr<BagContents> contents;  // not inline: a round holds one BagRead per bag
  std::string error;
};

// Held by a reader thread while it forks a child and while it handles what came through its pipe:
// so `take` calls come one at a time, and no reader thread allocates while another forks (a
// child forked then could inherit a locked allocator; seen under ASan, whose allocator has no
// fork handler here).
std::mutex reader_lock;

// Takes the contents of job i's bag as its frame arrives (from the reader threads, one at a time).
using TakeBag = std::function<void(std::size_t, BagRead&)>;

// The child of read_bags_in_child: reads jobs[first...] and sends a frame per bag into the pipe,
// then _exit (no destructors, no atexit).
[[noreturn]] void read_bags_into_pipe(const std::vector<BagJob>& jobs, std::size_t first, const int fds[2]) {
  ::close(fds[0]);
  auto bag = std::make_unique<rosbag::Bag>();
  for (std::size_t i = first; i < jobs.size(); ++i) {
    std::uint8_t status = 0;
    std::vector<std::uint8_t> payload;
    try {
      payload = serialize(read_bag(*bag, jobs[i].file, jobs[i].states));
    } catch (const std::exception& ex) {
      bag = std::make_unique<rosbag::Bag>();
      status = dynamic_cast<const Skip*>(&ex) ? 1 : 2;
      const std::string what = ex.what();
      payload.assign(what.begin(), what.end());
    }
    const auto index = static_cast<std::uint32_t>(i), size = static_cast<std::uint32_t>(payload.size());
    if (!write_all(fds[1], &index, 4) || !write_all(fds[1], &status, 1) || !write_all(fds[1], &size, 4) ||
        !write_all(fds[1], payload.data(), payload.size()))
      ::_exit(3);
  }
  ::_exit(0);
}

// Reads the bags in order in a child process. rosbag trusts a bag's index: a damaged offset makes
// it read out of bounds and crash (one flipped byte in an index record is enough). In a child that
// costs the bag, not the aggregator: a new child goes on with the next bag. One child reads many
// bags because forks are dear (a child per bag made reading a batch several times slower). The child
// sends a frame per bag: index (4 bytes), status (1: 0 contents, 1 Skip, 2 other error), payload
// length (4) and payload (the serialized contents or the message); the parent takes each frame
// as it arrives, so no more than one bag's frame is buffered, and hands a frame with contents to
// `take` at once (index into `jobs`); the others stay in the result.
std::vector<BagRead> read_bags_in_child(const std::vector<BagJob>& jobs, const TakeBag& take) {
  std::exception_ptr take_error;  // from `take`: rethrown once the child has ended
  std::vector<BagRead> out(jobs.size());
  std::vector<bool> done(jobs.size(), false);
  std::size_t first = 0;
  while (first < jobs.size()) {
    int fds[2];
    pid_t pid;
    {
      // Another reader thread forking between this pipe's creation and the close of its write
      // end below would give its child a copy of that end, and this pipe's end of file would then
      // wait for that child as well.
      std::lock_guard<std::mutex> lock(reader_lock);
      if (::pipe2(fds, O_CLOEXEC) != 0)
        throw BatchReadError(std::string("cannot read bags: pipe: ") + std::strerror(errno));
      pid = ::fork();
      if (pid == 0) read_bags_into_pipe(jobs, first, fds);  // the child; does not return
      ::close(fds[1]);
    }
    if (pid < 0) {
      ::close(fds[0]);
      throw BatchReadError(std::string("cannot read bags: fork: ") + std::strerror(errno));
    }
    std::vector<std::uint8_t> data;  // data[at...] is not yet taken
    std::size_t at = 0;
    const auto take_frames = [&] {  // whole frames (a crash may cut the last one)
      while (at + 9 <= data.size()) {
        std::uint32_t index, size;
        std::memcpy(&index, &data[at], 4);
        std::memcpy(&size, &data[at + 5], 4);
        if (index >= jobs.size() || at + 9 + size > data.size()) break;
        std::uint8_t* payload = &data[at + 9];
        const std::uint8_t status = data[at + 4];
        if (status == 0) {
          out[index].contents = std::make_unique<BagContents>(deserialize(payload, size));
          try {
            if (!take_error) take(index, out[index]);
          } catch (...) {
            take_error = std::current_exception();
          }
        } else {
          const std::string what(payload, payload + size);
          out[index].error = status == 1 ? what : "unreadable bag (truncated or corrupted): " + what;
        }
        done[index] = true;
        at += 9 + size;
      }
      data.erase(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(at));
      at = 0;
    };
    char chunk[1 << 16];
    for (;;) {
      const ssize_t n = ::read(fds[0], chunk, sizeof chunk);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      std::lock_guard<std::mutex> lock(reader_lock);
      data.insert(data.end(), chunk, chunk + n);
      take_frames();
    }
    ::close(fds[0]);
    int wstatus = 0;
    while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
    }
    if (take_error) std::rethrow_exception(take_error);
    while (first < jobs.size() && done[first]) ++first;
    if (first == jobs.size()) break;
    // The bag in hand when the child ended.
    out[first].error = WIFSIGNALED(wstatus)
                           ? std::string("unreadable bag (damaged: reading it crashed the bag reader with ") +
                                 ::strsignal(WTERMSIG(wstatus)) + ")"
                           : "unreadable bag (the bag reader ended without an answer, exit status " +
                                 std::to_string(WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1) + ")";
    done[first++] = true;
  }
  return out;
}

// The bags read by one child per core at once (read_bags_in_child; bag i goes to reader
// i mod readers), each child's pipe drained by a thread of its own, which hands each bag's contents
// to `take` (index into `jobs`; one call at a time) as they arrive.
std::vector<BagRead> read_bags_isolated(const std::vector<BagJob>& jobs, const TakeBag& take) {
  const std::size_t readers =
      std::min<std::size_t>(std::max(1u, std::thread::hardware_concurrency()), std::max<std::size_t>(1, jobs.size()));
  std::vector<std::vector<BagJob>> part(readers);
  for (std::size_t i = 0; i < jobs.size(); ++i) part[i % readers].push_back(jobs[i]);
  std::vector<std::vector<BagRead>> read(readers);
  std::vector<std::exception_ptr> error(readers);
  std::vector<std::thread> threads;
  std::unique_lock<std::mutex> starting(reader_lock);  // no thread forks while this one allocates
  for (std::size_t r = 0; r < readers; ++r)
    threads.emplace_back([&, r] {
      try {
        read[r] = read_bags_in_child(part[r], [&](std::size_t i, BagRead& bag) {
          take(i * readers + r, bag);
        });
      } catch (...) {
        error[r] = std::current_exception();
      }
    });
  starting.unlock();
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : error)
    if (e) std::rethrow_exception(e);
  std::vector<BagRead> out(jobs.size());
  for (std::size_t i = 0; i < jobs.size(); ++i) out[i] = std::move(read[i % readers][i / readers]);
  return out;
}

// A run_info's parameters_yaml as check_run compares it: its config_key and study point, or why
// it is not a configuration.
struct ParsedParameters {
  std::string key, error;
  std::size_t point = ~std::size_t{0};
};

// parameters_yaml texts already parsed: the runs of one mu (of one point) share one text, and YAML
// parsing was most of the reading time.
class ParametersCache {
 public:
  const ParsedParameters& parse(const std::string& text) {
    const auto found = parsed_.find(text);
    if (found != parsed_.end()) return found->second;
    ParsedParameters p;
    try {
      const YAML::Node n = YAML::Load(text);
      p.key = config_key(parse_config(n));
      try {
        p.point = n["study"]["point"].as<std::size_t>();
      } catch (const YAML::Exception&) {
      }
    } catch (const std::exception& ex) {
      p.error = ex.what();
    }
    return parsed_.emplace(text, std::move(p)).first->second;
  }

 private:
  std::map<std::string, ParsedParameters> parsed_;
};

// The run record of bag `read` of run `e`, if it is that run of this batch (its Poincaré points
// moved out of `read`); else throws Skip.
RunRecord check_run(BagRead& read, const ManifestRun& e, const FolderManifest& manifest, ParametersCache& parameters) {
  const auto require = [](bool ok, const std::string& why) {
    if (!ok) throw Skip(why);
  };
  if (!read.contents) throw Skip(read.error);
  BagContents& bag = *read.contents;
  const int infos = static_cast<int>(bag.infos), summaries = static_cast<int>(bag.summaries);
  require(infos == 1, "has " + std::to_string(infos) + " " + kRunInfoTopic + " messages, expected 1");
  require(summaries == 1, summaries == 0 ? std::string("has no ") + kSummaryTopic + " (the run did not finish)"
                                         : "has " + std::to_string(summaries) + " " + kSummaryTopic + " messages, expected 1");
  const RunInfo* info = &bag.info;
  const RunSummary* summary = &bag.summary;

  // Is it this run of this batch?
  const ModelConfig& c = manifest.model;
  require(info->kind == to_string(e.kind) && info->realization == e.realization && same_value(info->mu, e.mu),
          "run_info is run (" + info->kind + ", realization " + std::to_string(info->realization) + ", mu " +
              std::to_string(info->mu) + "), the manifest lists (" + to_string(e.kind) + ", " +
              std::to_string(e.realization) + ", " + std::to_string(e.mu) + ") (a bag of another batch)");
  require(info->seed == c.seed, "run_info seed " + std::to_string(info->seed) + " differs from the batch's " +
                                    std::to_string(c.seed) + " (a bag of another batch)");
  const ParsedParameters& parsed = parameters.parse(info->parameters_yaml);
  if (!parsed.error.empty()) throw Skip("run_info parameters_yaml is not a valid configuration: " + parsed.error);
  const std::string& expected = manifest.study ? manifest.point_keys.at(e.point) : manifest.config_key;
  require(parsed.key == expected, "run_info configuration differs from the manifest's at " +
                                      first_difference(expected, parsed.key) + " (a bag of another batch)");
  if (manifest.study)
    require(parsed.point == e.point, "run_info study.point differs from the manifest's point " +
                                         std::to_string(e.point) + " (a bag of another batch)");
  require(same_value(info->time_step, c.run.time_step) && same_value(info->duration, c.run.duration),
          "run_info time_step/duration differ from the manifest's (a bag of another batch)");
  require(summary->run_name == e.name && summary->kind == to_string(e.kind) && summary->realization == e.realization &&
              same_value(summary->mu, e.mu),
          "summary is of run '" + summary->run_name + "', not '" + e.name + "'");
  require(summary->snapshot_delta.size() == summary->snapshot_times.size() &&
              summary->snapshot_delta_dot.size() == summary->snapshot_times.size(),
          "summary snapshot arrays differ in length");
  require(all_finite({summary->center_distance, summary->steady_state_time, summary->steady_state_time_fine,
                      summary->final_delta, summary->final_delta_dot, summary->final_phi}) &&
              all_finite(summary->snapshot_times) && all_finite(summary->snapshot_delta) &&
              all_finite(summary->snapshot_delta_dot),
          "summary holds a non-finite value");
  require(all_finite(bag.section_t) && all_finite(bag.section_delta) && all_finite(bag.section_delta_dot),
          std::string(kPoincareTopic) + " holds a non-finite value");

  RunRecord r;
  r.name = e.name;
  r.kind = e.kind;
  r.mu = e.mu;
  r.index = e.realization;
  r.point = e.point;
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
  r.section_times = std::move(bag.section_t);
  r.section_delta = std::move(bag.section_delta);
  r.section_delta_dot = std::move(bag.section_delta_dot);
  require(bag.bearings.size() <= 1, "has " + std::to_string(bag.bearings.size()) + " " + kBearingSummaryTopic +
                                        " messages, expected at most 1");
  if (!bag.bearings.empty()) {
    const BearingSummary& b = bag.bearings.front();
    require(b.run_name == e.name, std::string(kBearingSummaryTopic) + " is of run '" + b.run_name + "', not '" + e.name + "'");
    r.bearings = BearingForces{{b.mesh_force_mean, b.mesh_force_rms}, {b.pinion_fx_mean, b.pinion_fx_rms},
                               {b.pinion_fy_mean, b.pinion_fy_rms}, {b.wheel_fx_mean, b.wheel_fx_rms},
                               {b.wheel_fy_mean, b.wheel_fy_rms}};
    require(all_finite({b.mesh_force_mean, b.mesh_force_rms, b.pinion_fx_mean, b.pinion_fx_rms, b.pinion_fy_mean,
                        b.pinion_fy_rms, b.wheel_fx_mean, b.wheel_fx_rms, b.wheel_fy_mean, b.wheel_fy_rms}),
            std::string(kBearingSummaryTopic) + " holds a non-finite value");
  }
  return r;
}

// The folders named, each once (canonical paths, in the order given).
std::vector<fs::path> distinct_folders(const std::vector<std::string>& folder_args) {
  std::vector<fs::path> folders;
  for (const std::string& f : folder_args) {
    std::error_code ec;
    if (!fs::is_directory(f, ec)) throw BatchReadError("batch folder '" + f + "' does not exist or is not a folder");
    const fs::path canonical = fs::canonical(f);
    if (std::find(folders.begin(), folders.end(), canonical) == folders.end()) folders.push_back(canonical);
  }
  if (folders.empty()) throw BatchReadError("no batch folder given");
  return folders;
}

// Each run listed in a manifest, by name, with the manifest that listed it first.
using Listed = std::map<std::string, std::pair<ManifestRun, const FolderManifest*>>;

// The folders' manifests, checked to be one batch (one model configuration, format, grid and
// monte_carlo content), the runs they list, and the shards seen (shard_count -> indices).
// Not copyable: `listed` points into `manifests`.
struct Listing {
  std::vector<FolderManifest> manifests;
  Listed listed;
  std::map<int, std::set<int>> shards;
  Listing() = default;
  Listing(const Listing&) = delete;
  Listing& operator=(const Listing&) = delete;
};

void list_runs(const std::vector<fs::path>& folders, Listing& listing) {
  std::vector<FolderManifest>& manifests = listing.manifests;
  Listed& listed = listing.listed;
  std::map<int, std::set<int>>& shards = listing.shards;
  for (const fs::path& folder : folders) {
    const auto paths = manifest_paths(folder);
    if (paths.empty())
      throw BatchReadError("batch folder '" + folder.string() + "' has no manifest.yaml (not a batch folder, or the batch has not started)");
    for (const fs::path& p : paths) manifests.push_back(parse_manifest(p));
  }
  for (const FolderManifest& m : manifests) {
    if (m.study != manifests.front().study || m.grid != manifests.front().grid)
      throw BatchReadError("manifests " + manifests.front().path.string() + " and " + m.path.string() +
                           " belong to different batches: their formats or study grids differ");
    if (m.config_key != manifests.front().config_key)
      throw BatchReadError("manifests " + manifests.front().path.string() + " and " + m.path.string() +
                           " belong to different batches: their configurations differ at " +
                           first_difference(manifests.front().config_key, m.config_key));
    if (m.content != manifests.front().content)
      throw BatchReadError("manifests " + manifests.front().path.string() + " and " + m.path.string() +
                           " belong to different batches: their monte_carlo sections differ (" +
                           manifests.front().content + " vs " + m.content + ")");
    shards[m.shard_count].insert(m.shard_index);
    for (const ManifestRun& e : m.runs) {
      const auto [it, inserted] = listed.emplace(e.name, std::make_pair(e, &m));
      const ManifestRun& had = it->second.first;
      if (!inserted && (had.kind != e.kind || had.realization != e.realization || !same_value(had.mu, e.mu) || had.point != e.point))
        throw BatchReadError("run " + e.name + " is listed differently in " + it->second.second->path.string() +
                             " and " + m.path.string());
    }
  }
}

// The batch's axes and points: a study's from its manifest, a mu sweep's (format 1) one point per
// mu, ascending as its report; each listed run gets its point.
void set_points(BatchInputs& in, Listing& listing) {
  const std::vector<FolderManifest>& manifests = listing.manifests;
  Listed& listed = listing.listed;
  if (manifests.front().study) {
    for (std::size_t a = 0; a < manifests.front().axes.size(); ++a) {
      SweepAxis axis = manifest_axes(manifests.front())[a];
      for (const auto& p : manifests.front().points)
        if (std::find(axis.values.begin(), axis.values.end(), p[a]) == axis.values.end()) axis.values.push_back(p[a]);
      in.axes.push_back(axis);
    }
    in.points = manifests.front().points;
  } else {  // format 1, a mu sweep: one point per mu, ascending (as its report)
    std::set<double> mus;
    for (const auto& [name, entry] : listed) mus.insert(entry.first.mu);
    in.axes.push_back({kFrictionKey, std::vector<double>(mus.begin(), mus.end()), {}});
    for (double mu : mus) in.points.push_back({mu});
    for (auto& [name, entry] : listed)
      entry.first.point = static_cast<std::size_t>(std::distance(mus.begin(), mus.find(entry.first.mu)));
  }
}

// A shard none of whose manifests was found is reported as missing.
void note_missing_shards(BatchInputs& in, const std::map<int, std::set<int>>& shards) {
  for (const auto& [count, seen] : shards)
    for (int i = 0; i < count; ++i)
      if (!seen.count(i)) {
        in.missing.push_back("shard " + std::to_string(i) + " of " + std::to_string(count) + " (no manifest found)");
        ROS_WARN("batch: shard %d of %d has no manifest in the folders given; its runs are not counted", i, count);
      }
}

void skip(BatchInputs& in, const fs::path& file, const std::string& reason) {
  ROS_WARN("batch: skipping %s: %s", file.c_str(), reason.c_str());
  in.skipped.push_back({file.string(), reason});
}

// Files no manifest accounts for: unfinished bags and bags not listed.
void skip_unlisted(BatchInputs& in, const std::vector<fs::path>& folders, const Listed& listed) {
  std::set<fs::path> referenced;
  for (const auto& [name, entry] : listed)
    for (const fs::path& folder : folders) referenced.insert(folder / entry.first.file);
  for (const fs::path& folder : folders)
    for (const auto& f : fs::directory_iterator(folder)) {
      const std::string name = f.path().filename().string();
      if (is_active_file(name)) skip(in, f.path(), "unfinished (.active): the run was in flight or abandoned");
      else if (is_bag_file(name) && !referenced.count(f.path())) skip(in, f.path(), "not listed in any manifest of the batch");
    }
}

// A listed run's bag in one folder: the first usable one is used, the later ones are duplicates.
struct Candidate {
  fs::path folder, file;
  bool tried = false;
  std::optional<RunRecord> record;
  std::string reason;  // why it is not usable
};
using Candidates = std::map<std::string, std::vector<Candidate>>;

Candidates candidates_of(const Listed& listed, const std::vector<fs::path>& folders) {
  Candidates candidates;
  for (const auto& [name, entry] : listed)
    for (const fs::path& folder : folders)
      if (fs::exists(folder / entry.first.file)) {
        Candidate c;
        c.folder = folder;
        c.file = folder / entry.first.file;
        candidates[name].push_back(std::move(c));
      }
  return candidates;
}

// Reads the candidates in rounds: each reads the next bag of every run still without a usable one,
// until none is left to try.
void read_candidates(BatchInputs& in, Candidates& candidates, const Listed& listed, const ReadOptions& options) {
  ParametersCache parameters;
  for (;;) {
    std::vector<BagJob> jobs;
    std::vector<std::pair<Candidate*, const std::pair<ManifestRun, const FolderManifest*>*>> round;
    for (auto& [name, list] : candidates) {
      const auto& entry = listed.at(name);
      const ManifestRun& e = entry.first;
      const bool wants_series = options.on_series && options.wants_series && options.wants_series(e);
      for (Candidate& c : list) {
        if (c.record) break;
        if (c.tried) continue;
        jobs.push_back({c.file, wants_series});
        round.emplace_back(&c, &entry);
        break;
      }
    }
    if (jobs.empty()) break;
    // Each bag as it arrives: checked, its series handed to options.on_series, then dropped, so
    // that no more than one bag's series per reader is held at a time.
    const auto take = [&](std::size_t i, BagRead& read) {
      Candidate& c = *round[i].first;
      c.tried = true;
      try {
        c.record = check_run(read, round[i].second->first, *round[i].second->second, parameters);
        const RunSeries& series = read.contents->series;
        if (options.on_series && !series.t.empty()) options.on_series(in, *c.record, series);
      } catch (const Skip& ex) {
        c.reason = ex.what();
      }
      read.contents.reset();
    };
    const std::vector<BagRead> reads = read_bags_isolated(jobs, take);
    for (std::size_t i = 0; i < reads.size(); ++i) {
      Candidate& c = *round[i].first;
      if (c.tried) continue;
      c.tried = true;
      c.reason = reads[i].error;  // unreadable: no contents came
    }
  }
}

// The runs used, in the listed order, the skipped duplicates and unusable bags, and the runs with
// no usable bag; throws if a folder gave nothing.
void choose_runs(BatchInputs& in, Candidates& candidates, const Listed& listed, const std::vector<fs::path>& folders) {
  std::map<fs::path, std::size_t> usable;  // runs each folder provides
  for (const auto& [name, entry] : listed) {
    std::string used;
    for (Candidate& c : candidates[name]) {
      if (!used.empty()) {  // the folder still contributes this run
        skip(in, c.file, "duplicate of " + used + " (not read)");
        ++usable[c.folder];
      } else if (c.record) {
        in.runs.push_back(std::move(*c.record));
        used = c.file.string();
        ++usable[c.folder];
      } else {
        skip(in, c.file, c.reason);
      }
    }
    if (used.empty()) {
      ROS_WARN("batch: run %s has no usable bag", name.c_str());
      in.missing.push_back(name);
    }
  }
  for (const fs::path& folder : folders)
    if (!usable[folder])
      throw BatchReadError("batch folder '" + folder.string() + "' has no usable bag (" +
                           std::to_string(in.skipped.size()) + " skipped, " + std::to_string(in.missing.size()) +
                           " runs missing)");
}

}  // namespace

BatchInputs read_batches(const std::vector<std::string>& folder_args, const ReadOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  BatchInputs in;
  const std::vector<fs::path> folders = distinct_folders(folder_args);
  for (const auto& f : folders) in.folders.push_back(f.string());
  Listing listing;
  list_runs(folders, listing);
  in.config = listing.manifests.front().model;
  in.expected_runs = listing.listed.size();
  set_points(in, listing);
  note_missing_shards(in, listing.shards);
  skip_unlisted(in, folders, listing.listed);
  Candidates candidates = candidates_of(listing.listed, folders);
  read_candidates(in, candidates, listing.listed, options);
  choose_runs(in, candidates, listing.listed, folders);
  ROS_INFO("batch: %zu of %zu runs read from %zu folder(s) in %.2f s; %zu bags skipped, %zu missing (runs or shards)",
           in.runs.size(), in.expected_runs, folders.size(),
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), in.skipped.size(),
           in.missing.size());
  return in;
}

bool batch_complete(const std::string& folder) {
  try {
    const auto paths = manifest_paths(folder);
    if (paths.empty()) return false;
    for (const fs::path& p : paths)
      for (const ManifestRun& e : parse_manifest(p).runs)
        if (!fs::exists(fs::path(folder) / e.file)) return false;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::string manifests_signature(const std::string& folder) {
  std::ostringstream out;
  try {
    for (const fs::path& p : manifest_paths(folder)) {
      struct stat st {};
      if (::stat(p.c_str(), &st) != 0) continue;
      out << p.filename().string() << ' ' << st.st_ino << ' ' << st.st_size << ' ' << st.st_mtim.tv_sec << '.'
          << st.st_mtim.tv_nsec << '\n';
    }
  } catch (const std::exception&) {  // the folder is not there (yet)
  }
  return out.str();
}

}  // namespace gear_dynamics
