// Safety over time, first passage out of the safe set, Kaplan-Meier survival and Gaussian kernel
// density estimates (doc/nonlinear-dynamics.md §6, §7). Pure functions on recorded samples.
#pragma once

#include <cstddef>
#include <vector>

#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics {

// Safe intervals: Interval (closed [lo, hi]) of the analysis settings.

// Samples of R runs at J common times: value[r][j].
struct RecordedRuns {
  std::vector<double> time;
  std::vector<std::vector<double>> delta, velocity;
};

// At each recorded time: P(delta in I_delta and delta_dot in I_v), P(delta in I_delta),
// P(delta_dot in I_v), each with its Wilson interval.
struct SafetySeries {
  std::vector<double> time;
  std::vector<Proportion> joint, delta_only, velocity_only;
};
SafetySeries safety_over_time(const RecordedRuns& runs, const Interval& delta, const Interval& velocity,
                              double confidence = kConfidence);

// First recorded time t >= settle at which a run is outside the safe set (both intervals); runs that
// stay inside to the last recorded time are censored there (event = false).
struct FirstPassage {
  std::vector<double> time;
  std::vector<bool> event;
};
FirstPassage first_passage(const RecordedRuns& runs, const Interval& delta, const Interval& velocity, double settle);

// Kaplan-Meier estimate S(t) at each distinct event time, with Greenwood's variance and the
// log(-log) confidence interval (Kalbfleisch-Prentice), which stays inside [0, 1].
struct KaplanMeier {
  std::vector<double> time, survival, low, high;
  std::vector<std::size_t> at_risk, events;
};
KaplanMeier kaplan_meier(const std::vector<double>& time, const std::vector<bool>& event,
                         double confidence = kConfidence);
// S(t) of a Kaplan-Meier curve (right-continuous step function; 1 before the first event).
double survival_at(const KaplanMeier& km, double t);

// Gaussian KDE; bandwidth <= 0 selects Silverman's rule of thumb
// 0.9 min(sd, IQR / 1.34) n^(-1/5) (Silverman 1986, Eq. 3.31).
double silverman_bandwidth(const std::vector<double>& values);
std::vector<double> gaussian_kde(const std::vector<double>& values, const std::vector<double>& grid,
                                 double bandwidth = 0);

}  // namespace gear_dynamics
