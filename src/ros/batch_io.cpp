#include "gear_dynamics/ros/batch_io.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "gear_dynamics/engine/instruction_set.hpp"

namespace gear_dynamics {

namespace fs = std::filesystem;

namespace {

std::string emit(const YAML::Node& n) {
  YAML::Emitter out;
  out << n;
  return out.c_str();
}

fs::path bag_path(const std::string& folder, const std::string& name) { return fs::path(folder) / bag_file_name(name); }
fs::path active_path(const std::string& folder, const std::string& name) {
  return fs::path(folder) / active_file_name(name);
}

// Why the folder cannot take this shard of this batch, or "" if it can. Shards of one batch may
// share a folder (each writes its own manifest); anything else is another batch.
std::string refusal(const fs::path& dir, const YAML::Node& config, const BatchSettings& s, const std::string& format) {
  bool manifests = false, other_files = false;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string file = entry.path().filename().string();
    if (!is_manifest_file(file)) {
      other_files = other_files || !is_temporary_file(file);
      continue;
    }
    manifests = true;
    Manifest m;
    try {
      m = read_manifest(entry.path().string());
    } catch (const ManifestError& e) {
      return std::string("it holds a manifest that is not valid (") + e.what() + ")";
    }
    if (m.format() != format) return entry.path().string() + " is not a " + format + " manifest";
    if (emit(m.config) != emit(config)) return "it holds a batch with a different configuration (" + file + ")";
    if (m.numbers != kNumbersGeneration)
      return "its bags hold numbers of generation " + std::to_string(m.numbers) + " (" + file + "), this build makes generation " +
             std::to_string(kNumbersGeneration) + ": the same settings give other results now";
    if (m.shard_count != s.shard_count)
      return "it holds the same batch split into " + std::to_string(m.shard_count) + " shards (" + file + "), not " +
             std::to_string(s.shard_count);
  }
  return !manifests && other_files ? "it is not empty and holds no manifest" : "";
}

}  // namespace

const char* manifest_format(const Study& study) { return study.swept() ? kManifestFormatStudy : kManifestFormat; }

RunInfo run_info(const ModelConfig& model, const RunSpec& run) { return RunInfos(model)(run); }

RunInfo run_info(const Study& study, const RunSpec& run) { return RunInfos(study)(run); }

RunInfo RunInfos::operator()(const RunSpec& run) {
  const ModelConfig config = study_ ? run_config(*study_, run) : run_config(model_, run);
  const double sigma = (study_ ? run_lane(*study_, run) : run_lane(model_, run)).sigma;
  return make_run_info(config, run.kind, run.index, run.mu, sigma, model_.run.duration, parameters(config, run));
}

const std::string& RunInfos::parameters(const ModelConfig& config, const RunSpec& run) {
  const auto key = std::make_tuple(run.point, run.mu, run.mesh_phase);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = parameters_.find(key); it != parameters_.end()) return it->second;  // map: stays put
  }
  std::string text = emit(to_yaml(config));
  if (study_ && study_->swept()) {
    YAML::Node n = YAML::Load(text);
    const StudyPoint& p = study_->points.at(run.point);
    n["study"]["point"] = p.index;
    for (std::size_t a = 0; a < study_->axes.size(); ++a) {
      const SweepAxis& axis = study_->axes[a];
      if (axis.text()) n["study"]["values"][axis.key] = axis.value_text(p.values[a]);
      else n["study"]["values"][axis.key] = p.values[a];
    }
    text = emit(n);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  return parameters_.emplace(key, std::move(text)).first->second;
}

namespace {

// bag_complete with a Bag to reopen (a new rosbag::Bag crawls the ROS packages for its encryptor
// plugin: dearer than reading a small bag). After an error the Bag is replaced by a fresh one.
bool bag_complete(std::unique_ptr<rosbag::Bag>& bag, const std::string& path, const RunInfo& expected,
                  bool with_section) {
  try {
    bag->open(path, rosbag::bagmode::Read);
    bool complete = false;
    {
      rosbag::View info(*bag, rosbag::TopicQuery(kRunInfoTopic));
      if (info.size() == 1) {
        const RunInfo::ConstPtr stored = info.begin()->instantiate<RunInfo>();
        complete = stored && *stored == expected &&
                   (!with_section || rosbag::View(*bag, rosbag::TopicQuery(kPoincareTopic)).size() > 0) &&
                   rosbag::View(*bag, rosbag::TopicQuery(kSummaryTopic)).size() == 1;
      }
    }
    bag->close();
    return complete;
  } catch (const std::exception&) {  // rosbag::BagException, ros::Exception: unreadable
    bag = std::make_unique<rosbag::Bag>();
    return false;
  }
}

// Which runs already have a complete bag in the folder, checked by the batch's threads at once
// (runs i, i + threads, ...): on resuming a finished batch this check is most of the node's start.
// The Bags are made before the threads start: a Bag's constructor loads a plugin.
std::vector<char> complete_bags(const Study& study, const BatchSettings& settings, const std::vector<RunSpec>& runs) {
  std::vector<char> complete(runs.size(), 0);
  RunInfos infos(study);
  const std::size_t threads =
      std::clamp<std::size_t>(static_cast<std::size_t>(batch_threads(settings)), 1, std::max<std::size_t>(1, runs.size()));
  std::vector<std::unique_ptr<rosbag::Bag>> readers;
  for (std::size_t t = 0; t < threads; ++t) readers.push_back(std::make_unique<rosbag::Bag>());
  std::vector<std::exception_ptr> error(threads);
  const auto check = [&](std::size_t t) {
    try {
      for (std::size_t i = t; i < runs.size(); i += threads) {
        const fs::path bag = bag_path(settings.output_dir, runs[i].name);
        complete[i] = fs::exists(bag) &&
                      bag_complete(readers[t], bag.string(), infos(runs[i]), records_section(study, runs[i]));
      }
    } catch (...) {
      error[t] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(check, t);
  check(0);
  for (std::thread& th : pool) th.join();
  for (const std::exception_ptr& e : error)
    if (e) std::rethrow_exception(e);
  return complete;
}

}  // namespace

bool bag_complete(const std::string& path, const RunInfo& expected, bool with_section) {
  auto bag = std::make_unique<rosbag::Bag>();
  return bag_complete(bag, path, expected, with_section);
}

bool records_section(const Study& study, const RunSpec& run) {
  if (run.kind == RunKind::Stochastic) return false;
  const ModelConfig& c = study.points.at(run.point).config;
  GearInputs gear = c.gear;
  gear.mesh_phase = run.mesh_phase;
  return first_mesh_period_start(derive(gear)) <= c.run.duration;
}

std::vector<RunSpec> prepare_folder(const ModelConfig& model, const BatchSettings& settings,
                                    const std::vector<RunSpec>& runs) {
  return prepare_folder(make_study(model, settings), settings, runs);
}

std::vector<RunSpec> prepare_folder(const Study& study, const BatchSettings& settings,
                                    const std::vector<RunSpec>& runs) {
  const ModelConfig& model = study.base;
  const fs::path dir(settings.output_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("monte_carlo.output_dir = '" + settings.output_dir + "' cannot be created: " + ec.message());

  const std::string why = refusal(dir, manifest_config(model, settings), settings, manifest_format(study));
  if (!why.empty()) {
    if (!settings.overwrite) {
      throw std::runtime_error("monte_carlo.output_dir = '" + settings.output_dir + "' is refused: " + why +
                               ". Use another folder, or overwrite:=true to replace its bags and manifest.");
    }
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string f = entry.path().filename().string();
      if (is_bag_file(f) || is_active_file(f) || is_manifest_file(f)) fs::remove(entry.path());
    }
  }

  const std::vector<char> complete = complete_bags(study, settings, runs);
  std::vector<RunSpec> todo;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (complete[i]) continue;
    fs::remove(bag_path(settings.output_dir, runs[i].name));
    fs::remove(active_path(settings.output_dir, runs[i].name));
    todo.push_back(runs[i]);
  }
  return todo;
}

void write_manifest(const ModelConfig& model, const BatchSettings& settings,
                    const std::vector<RunSpec>& runs, bool complete) {
  write_manifest(make_study(model, settings), settings, runs, complete);
}

void write_manifest(const Study& study, const BatchSettings& settings,
                    const std::vector<RunSpec>& runs, bool complete) {
  Manifest m;
  m.study = study.swept();
  m.package_version = package_version();
  m.instruction_set = to_string(active_instruction_set());
  m.numbers = kNumbersGeneration;
  m.complete = complete;
  m.config = manifest_config(study.base, settings);
  m.shard_index = settings.shard_index;
  m.shard_count = settings.shard_count;
  if (m.study) {
    m.axes = study.keys();
    for (const SweepAxis& a : study.axes)
      if (a.text()) m.axis_labels[a.key] = a.labels;
    for (const StudyPoint& p : study.points) m.points.push_back(p.values);
  }
  for (const RunSpec& r : runs) m.runs.push_back({r.name, bag_file_name(r.name), r.kind, r.mu, r.index, r.point});
  write_manifest_file(settings.output_dir, m);
}

BagSink::BagSink(const ModelConfig& model, std::string folder, std::size_t queue_capacity)
    : model_(model), infos_(model_), folder_(std::move(folder)), capacity_(queue_capacity),
      thread_([this] { loop(); }) {}

BagSink::BagSink(const Study& study, std::string folder, std::size_t queue_capacity)
    : model_(study.base), study_(study), infos_(*study_), folder_(std::move(folder)), capacity_(queue_capacity),
      thread_([this] { loop(); }) {}

BagSink::~BagSink() {
  try {
    finish();
  } catch (...) {  // reported by an explicit finish(); a destructor must not throw
  }
}

void BagSink::started(const std::vector<RunSpec>& block) {
  std::vector<Item> items;
  for (const RunSpec& r : block) items.push_back({r.id, Open{r.name, infos_(r)}});
  push(std::move(items));
}

void BagSink::recorded(const std::vector<RunSpec>& block, const Ensemble& ensemble,
                       const Eigen::ArrayXd& center_distance) {
  std::vector<Item> items;
  items.reserve(block.size());
  const bool bearings = ensemble.model_state().size() > 0;  // gear_pair.model = bearings
  const double t = grid_time(ensemble.step_index(), ensemble.time_step());
  const model_step::MeshPoint mesh = bearings ? output_mesh_point(ensemble.mesh(), ensemble.time()) : model_step::MeshPoint{};
  for (std::size_t i = 0; i < block.size(); ++i) {
    const int lane = static_cast<int>(i);
    items.push_back({block[i].id, make_state(ensemble, lane, center_distance[lane])});
    if (bearings) {
      const BearingsOutputs o = bearings_outputs(ensemble, mesh, lane);
      items.push_back({block[i].id, BearingsSample{make_mesh_state(t, o, ensemble.model_state()(BearingsModel::kDelta, lane)),
                                                   make_bearing_wrench(t, kPinionBearingFrame, o.pinion_fx, o.pinion_fy),
                                                   make_bearing_wrench(t, kWheelBearingFrame, o.wheel_fx, o.wheel_fy)}});
    }
  }
  push(std::move(items));
}

void BagSink::finished(const std::vector<RunSpec>& block, const std::vector<RunResult>& results) {
  std::vector<Item> items;
  for (std::size_t i = 0; i < block.size(); ++i) {
    const RunSpec& r = block[i];
    Close close{{}, make_summary(r.name, r.kind, r.index, r.mu, r.mesh_phase, model_.run, results[i]), {}};
    if (results[i].bearings) close.bearings = make_bearing_summary(r.name, model_.run, *results[i].bearings);
    if (r.kind != RunKind::Stochastic)  // the section of the deterministic runs only (doc/batch-folder.md §5)
      for (const SectionPoint& p : results[i].section) close.section.push_back(make_poincare_point(p));
    items.push_back({r.id, std::move(close)});
  }
  push(std::move(items));
}

void BagSink::abandoned(const std::vector<RunSpec>& block) {
  std::vector<Item> items;
  for (const RunSpec& r : block) items.push_back({r.id, Abandon{}});
  push(std::move(items));
}

void BagSink::push(std::vector<Item>&& items) {
  std::unique_lock<std::mutex> lock(mutex_);
  // A batch larger than the whole capacity still goes in once the queue is empty.
  not_full_.wait(lock, [&] { return error_ || queued_ == 0 || queued_ + items.size() <= capacity_; });
  if (error_) std::rethrow_exception(error_);
  queued_ += items.size();
  queue_.push_back(std::move(items));
  not_empty_.notify_one();
}

void BagSink::loop() {
  for (;;) {
    std::vector<Item> batch;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      not_empty_.wait(lock, [&] { return !queue_.empty() || done_; });
      if (queue_.empty()) break;
      batch = std::move(queue_.front());
      queue_.pop_front();
      queued_ -= batch.size();
      not_full_.notify_all();
      if (error_) continue;  // drain without writing
    }
    try {
      for (Item& item : batch) write(item);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
      not_full_.notify_all();
    }
  }
  for (auto& kv : open_) {  // runs that never finished: their bags stay .active
    try {
      kv.second.bag->close();
    } catch (...) {  // e.g. a full disk: the file stays .active, unfinished
    }
  }
  open_.clear();
  timespec cpu{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu);
  cpu_seconds_ = static_cast<double>(cpu.tv_sec) + 1e-9 * static_cast<double>(cpu.tv_nsec);
}

void BagSink::write(Item& item) {
  try {
    write_bag(item);
  } catch (const std::exception& e) {  // the run's bag stays .active
    const auto b = open_.find(item.id);
    if (b == open_.end()) throw;
    const std::string file = active_path(folder_, b->second.name).string();
    open_.erase(b);  // closes the file unfinished: it stays .active
    // BagWriter's errors name the file already.
    throw std::runtime_error("cannot write " + (dynamic_cast<const BagWriteError*>(&e) ? "" : file + ": ") + e.what());
  }
}

void BagSink::write_bag(Item& item) {
  if (auto* open = std::get_if<Open>(&item.what)) {
    OpenBag& b = open_[item.id];
    b.name = open->name;
    b.bag = std::make_unique<BagWriter>();
    b.bag->open(active_path(folder_, b.name).string());
    // Bag times are the header stamps, except that run_info goes 1 ns before t = 0 and the summary
    // 1 ns after T: readers in time order (rosbag::View, rosbag play) meet them first and last
    // rather than tied with the states at t = 0 and T.
    b.bag->write(kRunInfoTopic, open->info.header.stamp - ros::Duration(0, 1), open->info);
  } else if (auto* state = std::get_if<GearState>(&item.what)) {
    open_.at(item.id).bag->write(kStateTopic, state->header.stamp, *state);
  } else if (auto* sample = std::get_if<BearingsSample>(&item.what)) {
    BagWriter& bag = *open_.at(item.id).bag;
    bag.write(kMeshTopic, sample->mesh.header.stamp, sample->mesh);
    bag.write(kPinionBearingTopic, sample->pinion.header.stamp, sample->pinion);
    bag.write(kWheelBearingTopic, sample->wheel.header.stamp, sample->wheel);
  } else if (auto* close = std::get_if<Close>(&item.what)) {
    OpenBag& b = open_.at(item.id);
    for (const PoincarePoint& p : close->section) b.bag->write(kPoincareTopic, sim_stamp(p.t), p);
    b.bag->write(kSummaryTopic, close->summary.header.stamp + ros::Duration(0, 1), close->summary);
    if (close->bearings) b.bag->write(kBearingSummaryTopic, close->bearings->header.stamp + ros::Duration(0, 1), *close->bearings);
    b.bag->close();
    fs::rename(active_path(folder_, b.name), bag_path(folder_, b.name));
    open_.erase(item.id);
    ++written_;
  } else {  // Abandon: close what was written, keep it .active
    auto it = open_.find(item.id);
    if (it == open_.end()) return;
    it->second.bag->close();
    open_.erase(it);
  }
}

void BagSink::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
    not_empty_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  if (error_) std::rethrow_exception(error_);
}

}  // namespace gear_dynamics
