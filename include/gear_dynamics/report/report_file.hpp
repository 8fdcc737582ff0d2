// One CSV or text file as every writer of report files opens it (the batch report, gear_analyze):
// created (or the writer fails naming it), listed in `written`, an optional header line, closed
// and checked when it goes out of scope.
#pragma once

#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "gear_dynamics/analysis/report_text.hpp"

namespace gear_dynamics {

class ReportFile {
 public:
  ReportFile(const std::filesystem::path& path, std::vector<std::string>& written, const std::string& header = "")
      : path_(path), out_(path) {
    if (!out_) throw std::runtime_error("cannot write " + path.string());
    written.push_back(path.string());
    if (!header.empty()) out_ << header << '\n';
  }
  ~ReportFile() noexcept(false) {
    out_.close();
    if (!out_ && std::uncaught_exceptions() == 0) throw std::runtime_error("error writing " + path_.string());
  }
  ReportFile(const ReportFile&) = delete;
  ReportFile& operator=(const ReportFile&) = delete;

  std::ostream& out() { return out_; }
  // A row that the caller goes on writing, starting with its key.
  std::ostream& line(const std::string& key) { return out_ << key; }
  // A whole CSV row: numbers as report_text::general, integers in full, text as it is.
  template <class... T>
  void row(const T&... fields) {
    std::size_t i = 0;
    ((out_ << (i++ ? "," : "") << field(fields)), ...);
    out_ << '\n';
  }

 private:
  static std::string field(double x) { return report_text::general(x); }
  static std::string field(const std::string& s) { return s; }
  static std::string field(const char* s) { return s; }
  template <class I, class = std::enable_if_t<std::is_integral_v<I>>>
  static std::string field(I x) { return std::to_string(x); }

  std::filesystem::path path_;
  std::ofstream out_;
};

}  // namespace gear_dynamics
