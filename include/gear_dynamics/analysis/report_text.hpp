// Numbers as the report writes them (report.md and its CSV files), shared by the batch report, the
// study report and the analyses over time, so one value reads the same everywhere.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

#include "gear_dynamics/maths/statistics.hpp"

namespace gear_dynamics::report_text {

// "0.123" with `decimals` places; "–" for NaN (no value).
inline std::string fixed(double x, int decimals) {
  if (std::isnan(x)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return buf;
}

// Appends x as %g with `digits` significant digits (10: the CSV files' precision). std::to_chars
// writes exactly printf's text, at a fraction of its cost (series.csv holds 600000 numbers).
inline void append_general(std::string& out, double x, int digits = 10) {
  char buf[64];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, digits).ptr);
}

inline std::string general(double x, int digits = 10) {
  std::string s;
  append_general(s, x, digits);
  return s;
}

// A percentage with its interval: "93.0 [85.0, 96.5]"; "–" without trials.
inline std::string percent(const Proportion& p) {
  if (p.trials == 0) return "–";
  return fixed(100 * p.estimate, 1) + " [" + fixed(100 * p.low, 1) + ", " + fixed(100 * p.high, 1) + "]";
}

}  // namespace gear_dynamics::report_text
