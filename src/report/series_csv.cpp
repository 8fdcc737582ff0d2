#include "gear_dynamics/report/series_csv.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

#include "gear_dynamics/analysis/report_text.hpp"
#include "gear_dynamics/report/report.hpp"

namespace gear_dynamics {

namespace fs = std::filesystem;

FigureSeries::FigureSeries(std::string folder, double mu) : folder_(std::move(folder)), mu_(mu) {}

FigureSeries::~FigureSeries() {
  for (const std::string& run : parts_) {
    std::error_code ec;
    fs::remove(part(run), ec);
  }
}

std::string FigureSeries::part(const std::string& run) const {
  return (fs::path(folder_) / ("series.csv." + run + ".part")).string();
}

bool FigureSeries::wants(RunKind kind, double mu, std::uint32_t index) const {
  return same_value(mu, mu_) && (kind == RunKind::S1 || (kind == RunKind::Stochastic && index <= 1));
}

void FigureSeries::add(const RunRecord& run, const RunSeries& series) {
  std::string rows;
  for (std::size_t j = 0; j < series.t.size(); ++j) {
    rows += run.name;
    rows += ',';
    rows += to_string(run.kind);
    rows += ',';
    report_text::append_general(rows, run.mu);
    rows += ',';
    rows += std::to_string(run.index);
    for (const double x : {series.t[j], series.delta[j] * kToPaperUnits, series.delta_dot[j] * kToPaperUnits,
                           series.phi[j] * kToPaperUnits}) {
      rows += ',';
      report_text::append_general(rows, x);
    }
    rows += '\n';
  }
  const std::string path = part(run.name);
  std::ofstream out(path, std::ios::binary);
  out << rows;
  if (!out.flush()) throw std::runtime_error("cannot write " + path);
  parts_.push_back(run.name);
}

std::string FigureSeries::write(const std::vector<RunRecord>& runs) {
  const std::string path = (fs::path(folder_) / "series.csv").string();
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "run,kind,mu,index,t[s],delta[mm],delta_dot[mm/s],phi[mm/s^2]\n";
  for (const RunRecord& r : runs) {
    const auto it = std::find(parts_.begin(), parts_.end(), r.name);
    if (it == parts_.end()) continue;
    out << std::ifstream(part(r.name), std::ios::binary).rdbuf();
    fs::remove(part(r.name));
    parts_.erase(it);
  }
  out.close();
  if (!out) throw std::runtime_error("error writing " + path);
  return path;
}

}  // namespace gear_dynamics
