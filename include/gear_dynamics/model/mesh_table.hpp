// The mesh over one schedule period as a table (doc/model.md §3): the mesh stiffness K, the friction
// factor f of Q = q3 + mu f and the static transmission error e as functions of the unwrapped
// pinion angle theta = phi0 + Omega t. Used wherever the mesh is not the paper's (square wave,
// constant friction sign, perfect teeth); MeshSchedule keeps the paper's in closed form.
#pragma once

#include <memory>
#include <vector>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/tooth_stiffness.hpp"

namespace gear_dynamics {

// Whether `gear` is the paper's mesh (the closed form of MeshSchedule), or needs a MeshTable.
bool is_paper_mesh(const GearInputs& in);

// Mesh periods after which the mesh repeats: 1 for identical teeth, else the revolutions of the gears
// whose teeth differ (a fault or a profile error), lcm(Z1, Z2) if both do.
int schedule_mesh_periods(const GearInputs& in);

// The tooth pairs in contact at one angle (doc/model.md §3): pair j (pinion tooth j mod Z1, wheel
// tooth j mod Z2) touches at x_j = x_b + Rb1 (theta - j phi_n) while x_j is in [x_a, x_e].
struct MeshContact {
  long pair = 0;
  double x = 0.0;          // distance of the contact from C1 along the line of action [m]
  double stiffness = 0.0;  // the pair's share of K [N/m]
};

class MeshTable {
 public:
  // The values at one angle.
  struct Values {
    double stiffness = 0.0;  // K [N/m]
    double friction = 0.0;   // f [1/kg]
    double error = 0.0;      // e [m]
    // sigma: the bearings model's friction force across the line of action per unit mu and mesh
    // force [-] (friction_share in engine/bearings.hpp): each pair's share of the force with its
    // sign (reversing) or its law's weight. Tabulated, not refined on: K, f and e set the nodes.
    double share = 0.0;
  };

  // Tabulates `gear`'s mesh: each piece between two jumps (a pair entering or leaving, a spall's
  // edge, the pitch point where friction reverses) on uniform nodes, refined until linear
  // interpolation is within `tolerance` of the model (relative to K; f and e likewise).
  explicit MeshTable(const GearPair& gear, double tolerance = 1e-4);

  double period() const { return period_; }  // the schedule period [rad]
  int mesh_periods() const { return mesh_periods_; }
  // The jumps in [0, period], increasing: the first is 0, the last `period`.
  const std::vector<double>& breaks() const { return breaks_; }
  int pieces() const { return static_cast<int>(breaks_.size()) - 1; }
  // The piece holding the local angle a in [0, period).
  int piece_of(double a) const;
  // Linear interpolation in piece i at local angle a, taken inside the piece (its limit at an end).
  Values at(int piece, double a) const;
  Values at(double a) const { return at(piece_of(a), a); }
  // de/da of that interpolation at a [m/rad]: the rate the kernel's straight-line e integrates with.
  double error_slope(int piece, double a) const;
  // The model itself (no interpolation) at local angle a, on the side of piece i.
  Values exact(int piece, double a) const;
  std::vector<MeshContact> contacts(double a) const;

  double max_stiffness() const { return max_stiffness_; }
  double max_friction() const { return max_friction_; }
  double min_piece() const { return min_piece_; }  // the shortest piece [rad]
  int nodes() const { return static_cast<int>(values_.size()); }

 private:
  struct Piece {
    double begin, end;  // [rad]
    int first, count;   // its nodes in values_: count + 1 uniform nodes from begin to end
  };
  // The model within mesh period m at its local angle phi, on the side of the piece [lo, hi] of the
  // period that holds phi; ref and next: the shares of K of pairs m and m + 1.
  struct Sample {
    Values values;
    double ref = 0.0, next = 0.0;
  };
  Sample evaluate(long m, double phi, double lo, double hi) const;
  double pair_stiffness(long pair, double x) const;
  // A friction law's term of f for the pair at x with `share` of the force (x_mid: its side of the
  // pitch point).
  double law_friction(double share, double x, double x_mid) const;
  double pair_error(long pair) const;
  bool pair_is_faulty(long pair) const;
  std::vector<double> period_breaks(long m) const;  // local angles in [0, phi_n], increasing
  void tabulate_period(long m, double tolerance);

  GearPair gear_;
  std::unique_ptr<const ToothPairStiffness> teeth_;  // the potential-energy model, else none
  int mesh_periods_ = 1;
  double period_ = 0.0;
  std::vector<double> breaks_;
  std::vector<Piece> pieces_;
  std::vector<Values> values_;
  double max_stiffness_ = 0.0, max_friction_ = 0.0, min_piece_ = 0.0;
};

// The table of `gear`, shared by every schedule of the same mesh in this process (blocks of a batch
// differ only in phase, speed or load).
std::shared_ptr<const MeshTable> shared_mesh_table(const GearPair& gear);

}  // namespace gear_dynamics
