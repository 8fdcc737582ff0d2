#include "gear_dynamics/config/aggregator_settings.hpp"

#include <filesystem>

#include "gear_dynamics/config/config.hpp"

namespace gear_dynamics {

std::string AggregatorSettings::report_dir() const {
  if (!report_folder.empty() || folders.empty()) return report_folder;
  return (std::filesystem::path(folders.front()) / "report").string();
}

const Section<AggregatorSettings>& aggregator_section() {
  static const Section<AggregatorSettings> section =
      Section<AggregatorSettings>("aggregator", "~")
          .key("folders", GD_MEMBER(folders), "batch folder(s); several folders (or one that several shards wrote into) merge into one report")
          .key("report_folder", GD_MEMBER(report_folder), "where report.md, the CSV files and the figures go (created if missing); empty: FIRST_FOLDER/report")
          .optional()
          .may_be_empty()
          .key("wait_for_batch", GD_MEMBER(wait_for_batch), "wait until every run the manifests list has its bag, or until batch_node has come and gone")
          .optional()
          .key("batch_node", GD_MEMBER(batch_node), "the batch node to watch while waiting: running while the master lists it and it answers at its "
               "XML-RPC address (rosnode ping's test; the master keeps listing a node killed by SIGKILL or a crash)")
          .optional()
          .key("wait_timeout", GD_MEMBER(wait_timeout), closed_open(0, kInf), "s",
               "give up waiting after this long (exit status 1); 0 = no limit")
          .optional()
          .key("plot_script", GD_MEMBER(plot_script), "the figure script (aggregator.launch sets scripts/plot_report.py unless plot:=false); empty: no figures")
          .optional()
          .may_be_empty()
          .key("series_mu", GD_MEMBER(series_mu), closed(0, kMaxFrictionCoefficient), "-",
               "mu whose S1, S2, S3 series go to series.csv (Figs. 5-7)")
          .optional()
          .key("exit_when_done", GD_MEMBER(exit_when_done), "exit after the report instead of keeping the latched topic")
          .optional();
  return section;
}

AggregatorSettings parse_aggregator_settings(const YAML::Node& params) {
  if (!params.IsMap())
    throw ConfigError("invalid configuration: the private parameters must be a map, got " + detail::show(params));
  std::vector<std::string> errors;
  AggregatorSettings s;
  SectionReader in(params, aggregator_section().prefix(), errors);
  aggregator_section().read(in, s);
  in.finish({"analysis"});
  s.analysis = read_analysis_settings(params, errors);
  detail::throw_if_errors(errors);
  return s;
}

}  // namespace gear_dynamics
