#include "gear_dynamics/model/mesh_table.hpp"

#include "gear_dynamics/model/friction_law.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

namespace gear_dynamics {

namespace {

long positive_mod(long j, long n) { return ((j % n) + n) % n; }

bool has_errors(const std::vector<double>& errors) {
  return std::any_of(errors.begin(), errors.end(), [](double e) { return e != 0.0; });
}

bool faults_gear(const GearInputs& in, FaultyGear gear) {
  return (in.crack.gear == gear && in.crack.depth > 0.0) ||
         (in.spall.gear == gear && in.spall.length > 0.0 && in.spall.width > 0.0);
}

}  // namespace

bool is_paper_mesh(const GearInputs& in) {
  return in.mesh_stiffness == MeshStiffnessModel::kSquareWave &&
         in.friction_direction == FrictionDirection::kConstant && in.friction_model == FrictionModel::kConstant &&
         !faults_gear(in, FaultyGear::kPinion) &&
         !faults_gear(in, FaultyGear::kWheel) && !has_errors(in.profile_errors.pinion) &&
         !has_errors(in.profile_errors.wheel);
}

int schedule_mesh_periods(const GearInputs& in) {
  const bool pinion = faults_gear(in, FaultyGear::kPinion) || has_errors(in.profile_errors.pinion);
  const bool wheel = faults_gear(in, FaultyGear::kWheel) || has_errors(in.profile_errors.wheel);
  if (pinion && wheel) return std::lcm(in.pinion_teeth, in.gear_teeth);
  return pinion ? in.pinion_teeth : wheel ? in.gear_teeth : 1;
}

MeshTable::MeshTable(const GearPair& gear, double tolerance) : gear_(gear) {
  if (gear.in.mesh_stiffness == MeshStiffnessModel::kPotentialEnergy)
    teeth_ = std::make_unique<const ToothPairStiffness>(gear);
  mesh_periods_ = schedule_mesh_periods(gear.in);
  period_ = mesh_periods_ * gear.mesh_period_angle;
  min_piece_ = period_;
  for (long m = 0; m < mesh_periods_; ++m) tabulate_period(m, tolerance);
  breaks_.push_back(period_);
}

bool MeshTable::pair_is_faulty(long pair) const {
  const GearInputs& in = gear_.in;
  const auto on = [&](FaultyGear g, int tooth) {
    return (g == FaultyGear::kPinion && positive_mod(pair, in.pinion_teeth) == tooth) ||
           (g == FaultyGear::kWheel && positive_mod(pair, in.gear_teeth) == tooth);
  };
  return (in.crack.depth > 0.0 && on(in.crack.gear, in.crack.tooth)) ||
         (in.spall.length > 0.0 && in.spall.width > 0.0 && on(in.spall.gear, in.spall.tooth));
}

double MeshTable::pair_stiffness(long pair, double x) const {
  x = std::min(std::max(x, gear_.x_a), gear_.x_e);
  return teeth_->stiffness(x, static_cast<int>(positive_mod(pair, gear_.in.pinion_teeth)),
                           static_cast<int>(positive_mod(pair, gear_.in.gear_teeth)));
}

double MeshTable::pair_error(long pair) const {
  const auto& p = gear_.in.profile_errors.pinion;
  const auto& w = gear_.in.profile_errors.wheel;
  const long i = positive_mod(pair, gear_.in.pinion_teeth), j = positive_mod(pair, gear_.in.gear_teeth);
  return (i < static_cast<long>(p.size()) ? p[i] : 0.0) + (j < static_cast<long>(w.size()) ? w[j] : 0.0);
}

std::vector<double> MeshTable::period_breaks(long m) const {
  const GearPair& g = gear_;
  const double rb1 = g.base_radius1, phi_n = g.mesh_period_angle, phi_m = g.single_pair_angle;
  std::vector<double> b{0.0, phi_m, phi_n};
  // Pair m is at x_b + Rb1 phi over the period, pair m + 1 at x_a + Rb1 (phi - phi_m) from phi_m on.
  const auto add_ref = [&](double x) {
    const double phi = (x - g.x_b) / rb1;
    if (phi > 0.0 && phi < phi_n) b.push_back(phi);
  };
  const auto add_next = [&](double x) {
    const double phi = phi_m + (x - g.x_a) / rb1;
    if (phi > phi_m && phi < phi_n) b.push_back(phi);
  };
  // The pitch point: friction reverses there, and a law has its kink (sliding through 0) there.
  if (g.in.friction_direction == FrictionDirection::kReversing || g.in.friction_model != FrictionModel::kConstant)
    add_ref(g.x_p), add_next(g.x_p);
  if (teeth_) {
    for (double x : teeth_->discontinuities(static_cast<int>(positive_mod(m, g.in.pinion_teeth)),
                                            static_cast<int>(positive_mod(m, g.in.gear_teeth))))
      add_ref(x);
    for (double x : teeth_->discontinuities(static_cast<int>(positive_mod(m + 1, g.in.pinion_teeth)),
                                            static_cast<int>(positive_mod(m + 1, g.in.gear_teeth))))
      add_next(x);
  }
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end(), [&](double x, double y) { return y - x < 1e-12 * phi_n; }), b.end());
  b.back() = phi_n;
  return b;
}

double MeshTable::law_friction(double share, double x, double x_mid) const {
  return pair_friction_weight(gear_, x, x_mid, share) * (gear_.c0 + gear_.c1 * x);
}

MeshTable::Sample MeshTable::evaluate(long m, double phi, double lo, double hi) const {
  const GearPair& g = gear_;
  // Inside the piece by a billionth of it: its limit at an end, not the neighbour's value.
  const double inset = 1e-9 * (hi - lo);
  phi = std::min(std::max(phi, lo + inset), hi - inset);
  const double mid = 0.5 * (lo + hi);
  const bool two = mid > g.single_pair_angle;
  const double x_ref = g.x_b + g.base_radius1 * phi;
  const double x_next = g.x_a + g.base_radius1 * (phi - g.single_pair_angle);
  Sample s;
  if (teeth_) {
    s.ref = pair_stiffness(m, x_ref);
    s.next = two ? pair_stiffness(m + 1, x_next) : 0.0;
  } else {
    s.ref = two ? 0.5 * g.k2 : g.k1;
    s.next = two ? 0.5 * g.k2 : 0.0;
  }
  const double K = s.ref + s.next;
  s.values.stiffness = K;
  if (g.in.friction_model != FrictionModel::kConstant) {
    const double x_ref_mid = g.x_b + g.base_radius1 * mid;
    const double x_next_mid = g.x_a + g.base_radius1 * (mid - g.single_pair_angle);
    s.values.friction = (law_friction(s.ref / K, x_ref, x_ref_mid) +
                         (two ? law_friction(s.next / K, x_next, x_next_mid) : 0.0));
    s.values.share = pair_friction_weight(g, x_ref, x_ref_mid, s.ref / K) +
                     (two ? pair_friction_weight(g, x_next, x_next_mid, s.next / K) : 0.0);
  } else if (g.in.friction_direction == FrictionDirection::kConstant) {
    s.values.friction = g.friction_factor(phi);  // the paper's reference pair (doc/model.md D4)
    s.values.share = 1.0;
  } else {
    // Each pair's friction by its share of the force, its sign that of its sliding velocity (the
    // side of the pitch point it is on, taken at the piece's middle).
    const auto signed_factor = [&](double x, double x_mid) {
      return (x_mid >= g.x_p ? 1.0 : -1.0) * (g.c0 + g.c1 * x);
    };
    const double x_ref_mid = g.x_b + g.base_radius1 * mid;
    const double x_next_mid = g.x_a + g.base_radius1 * (mid - g.single_pair_angle);
    s.values.friction = (s.ref * signed_factor(x_ref, x_ref_mid) +
                         (two ? s.next * signed_factor(x_next, x_next_mid) : 0.0)) / K;
    const auto sign = [&](double x_mid) { return x_mid >= g.x_p ? 1.0 : -1.0; };
    s.values.share = (s.ref * sign(x_ref_mid) + (two ? s.next * sign(x_next_mid) : 0.0)) / K;
  }
  s.values.error = (s.ref * pair_error(m) + s.next * pair_error(m + 1)) / K;
  return s;
}

void MeshTable::tabulate_period(long m, double tolerance) {
  const std::vector<double> b = period_breaks(m);
  const double start = m * gear_.mesh_period_angle;
  const double error_scale = std::max(std::fabs(pair_error(m)), std::fabs(pair_error(m + 1)));
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const double lo = b[i], hi = b[i + 1];
    // Doubles the nodes until the midpoints between nodes are within the tolerance of the model.
    std::vector<Sample> nodes;
    for (int count = 8;; count *= 2) {
      const double dx = (hi - lo) / count;
      nodes.clear();
      for (int k = 0; k <= count; ++k) nodes.push_back(evaluate(m, k == count ? hi : lo + k * dx, lo, hi));
      bool fine = true;
      for (int k = 0; k < count && fine; ++k) {
        const Values e = evaluate(m, lo + (k + 0.5) * dx, lo, hi).values;
        const Values& a = nodes[k].values;
        const Values& c = nodes[k + 1].values;
        const double K = 0.5 * (a.stiffness + c.stiffness), f = 0.5 * (a.friction + c.friction);
        const double err = 0.5 * (a.error + c.error);
        fine = std::fabs(K - e.stiffness) <= tolerance * e.stiffness &&
               std::fabs(f - e.friction) <= tolerance * (std::fabs(e.friction) + gear_.c0) &&
               std::fabs(err - e.error) <= tolerance * error_scale;
      }
      if (fine || count >= 4096) break;
    }
    breaks_.push_back(start + lo);
    pieces_.push_back({start + lo, start + hi, static_cast<int>(values_.size()), static_cast<int>(nodes.size()) - 1});
    for (const Sample& s : nodes) {
      values_.push_back(s.values);
      max_stiffness_ = std::max(max_stiffness_, s.values.stiffness);
      max_friction_ = std::max(max_friction_, s.values.friction);
    }
    min_piece_ = std::min(min_piece_, hi - lo);
  }
}

int MeshTable::piece_of(double a) const {
  const auto it = std::upper_bound(breaks_.begin(), breaks_.end(), a);
  const int i = static_cast<int>(it - breaks_.begin()) - 1;
  return std::min(std::max(i, 0), pieces() - 1);
}

MeshTable::Values MeshTable::at(int piece, double a) const {
  const Piece& p = pieces_[piece];
  const double u = std::min(std::max((a - p.begin) / (p.end - p.begin), 0.0), 1.0) * p.count;
  const int k = std::min(static_cast<int>(u), p.count - 1);
  const double w = u - k;
  const Values& lo = values_[p.first + k];
  const Values& hi = values_[p.first + k + 1];
  return {lo.stiffness + w * (hi.stiffness - lo.stiffness), lo.friction + w * (hi.friction - lo.friction),
          lo.error + w * (hi.error - lo.error), lo.share + w * (hi.share - lo.share)};
}

double MeshTable::error_slope(int piece, double a) const {
  const Piece& p = pieces_[piece];
  const double width = (p.end - p.begin) / p.count;
  const double u = std::min(std::max((a - p.begin) / (p.end - p.begin), 0.0), 1.0) * p.count;
  const int k = std::min(static_cast<int>(u), p.count - 1);
  return (values_[p.first + k + 1].error - values_[p.first + k].error) / width;
}

MeshTable::Values MeshTable::exact(int piece, double a) const {
  const Piece& p = pieces_[piece];
  const long m = static_cast<long>(std::floor(0.5 * (p.begin + p.end) / gear_.mesh_period_angle));
  const double start = m * gear_.mesh_period_angle;
  return evaluate(m, a - start, p.begin - start, p.end - start).values;
}

std::vector<MeshContact> MeshTable::contacts(double a) const {
  const int i = piece_of(a);
  const Piece& p = pieces_[i];
  const long m = static_cast<long>(std::floor(0.5 * (p.begin + p.end) / gear_.mesh_period_angle));
  const double start = m * gear_.mesh_period_angle;
  const Sample s = evaluate(m, a - start, p.begin - start, p.end - start);
  std::vector<MeshContact> out{{m, gear_.x_b + gear_.base_radius1 * (a - start), s.ref}};
  if (s.next > 0.0) out.push_back({m + 1, gear_.x_a + gear_.base_radius1 * (a - start - gear_.single_pair_angle), s.next});
  return out;
}

namespace {

// The bytes of every input the table depends on (not the phase, speed, damping or load).
std::string table_key(const GearInputs& in) {
  std::string k;
  const auto put = [&](const auto& x) { k.append(reinterpret_cast<const char*>(&x), sizeof x); };
  for (double x : {in.youngs_modulus, in.poisson_ratio, in.pinion_pitch_radius, in.gear_pitch_radius,
                   in.pressure_angle, in.face_width, in.addendum_coefficient, in.dedendum_coefficient,
                   in.profile_shift1, in.profile_shift2, in.bore_radius1, in.bore_radius2, in.crack.depth,
                   in.crack.angle, in.spall.length, in.spall.width, in.spall.position, in.density,
                   in.damping_ratio, in.reference_load, in.friction_load, in.oil_viscosity,
                   in.surface_roughness, in.pinion_speed})
    put(x);
  for (int x : {in.pinion_teeth, in.gear_teeth, static_cast<int>(in.mesh_stiffness),
                static_cast<int>(in.friction_direction), static_cast<int>(in.friction_model),
                static_cast<int>(in.crack.gear), in.crack.tooth,
                static_cast<int>(in.spall.gear), in.spall.tooth})
    put(x);
  for (const auto* list : {&in.profile_errors.pinion, &in.profile_errors.wheel}) {
    put(list->size());
    for (double x : *list) put(x);
  }
  return k;
}

}  // namespace

std::shared_ptr<const MeshTable> shared_mesh_table(const GearPair& gear) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const MeshTable>> tables;
  const std::string key = table_key(gear.in);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto it = tables.find(key);
    if (it != tables.end()) return it->second;
  }
  auto table = std::make_shared<const MeshTable>(gear);
  const std::lock_guard<std::mutex> lock(mutex);
  if (tables.size() >= 32) tables.clear();  // a long study: keep the memory bounded
  return tables.emplace(key, std::move(table)).first->second;
}

}  // namespace gear_dynamics
