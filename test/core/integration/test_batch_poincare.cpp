// Layers that must agree with each other, tested together: the batch runner's Poincare points
// (montecarlo) against the dynamics layer's section of the same run. Such tests include the
// layers they join (test/layers/check_layers.py allows it in this folder only).
#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/dynamics/poincare.hpp"
#include "gear_dynamics/montecarlo/batch.hpp"

#include "paper_config.hpp"

namespace gd = gear_dynamics;

// The batch's /gear/poincare points (engine PoincareSampler, run inside simulate() by run_batch) are
// the core's poincare_section of the same run, bit for bit: the same times t_k = t_0 + k T_m, the
// same grid states (GearLanes is bit-identical to the Ensemble) and the same interpolation. For the
// phase ensemble at 1000 rpm, t_0 = (64 - j) 46.875 steps: grid states for j = 0, 8, ..., 56, else
// interpolated. Also with a transient (as gear_analyze poincare): the tail of the same points.
TEST(Batch, PoincareSectionIsTheCoreSection) {
  gd::ModelConfig c = paper_config();
  c.run.duration = 0.03;
  c.run.window = 0.01;
  c.run.snapshot_times = {0.03};
  gd::BatchSettings s;
  s.mu = {0.04};
  s.realizations = 2;         // stochastic lanes share phase00's block (phi0 = 0, 100 Hz series)
  s.record_realizations = 1;
  s.threads = 1;
  s.block_lanes = 8;
  struct Collect : gd::BatchSink {
    std::map<std::size_t, gd::RunResult> results;
    void started(const std::vector<gd::RunSpec>&) override {}
    void recorded(const std::vector<gd::RunSpec>&, const gd::Ensemble&, const Eigen::ArrayXd&) override {}
    void finished(const std::vector<gd::RunSpec>& block, const std::vector<gd::RunResult>& r) override {
      for (std::size_t i = 0; i < block.size(); ++i) results[block[i].id] = r[i];
    }
    void abandoned(const std::vector<gd::RunSpec>&) override {}
  } sink;
  gd::BatchControl control;
  const std::vector<gd::RunSpec> runs = gd::plan_runs(c, s);
  gd::run_batch(c, runs, s, sink, control);
  ASSERT_EQ(sink.results.size(), runs.size());

  const double h = c.run.time_step;
  std::size_t interpolated = 0, on_grid = 0;
  for (const gd::RunSpec& run : runs) {
    if (run.kind == gd::RunKind::Stochastic) continue;
    gd::GearInputs gi = c.gear;
    gi.mesh_phase = run.mesh_phase;
    const gd::GearPair g = gd::derive(gi);
    const double offset = gd::first_mesh_period_start(g);
    for (double start : {0.0, 0.01}) {
      gd::GearLanes sys({gd::GearLaneSpec{gi, run.mu, c.load.initial_mean, c.initial}}, h);
      const auto core = gd::poincare_section(sys, {gd::mesh_period(g), offset, start, c.run.duration, {}});
      std::vector<gd::SectionPoint> batch;
      for (const gd::SectionPoint& p : sink.results.at(run.id).section)
        if (p.time >= start - 1e-9 * h) batch.push_back(p);
      ASSERT_EQ(batch.size(), core.size()) << run.name << " from " << start;
      ASSERT_GE(core.size(), 6u);  // 20 ms after the transient: 6 or 7 mesh periods of 3 ms
      for (std::size_t k = 0; k < core.size(); ++k) {
        EXPECT_EQ(batch[k].time, core[k].time) << run.name << " k " << k;
        EXPECT_EQ(batch[k].delta, core[k].x[0]) << run.name << " k " << k;
        EXPECT_EQ(batch[k].delta_dot, core[k].x[1]) << run.name << " k " << k;
        if (start == 0.0) ++(core[k].on_grid ? on_grid : interpolated);
      }
    }
  }
  EXPECT_GT(on_grid, 0u);
  EXPECT_GT(interpolated, on_grid);  // 56 of the 64 phase runs are off the grid
}
