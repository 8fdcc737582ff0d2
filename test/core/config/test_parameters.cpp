// One declaration per configuration section (section.hpp), checked against what else states the
// same facts: the shipped config files hold exactly the declared keys with the declared defaults
// (the settings structs' initializers), launch/aggregator.launch's argument defaults are the
// aggregator's, an optional key that is left out takes its default, and the parameter tables in
// the docs are the generated ones (gear_run --print-parameters SECTION).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "gear_dynamics/config/aggregator_settings.hpp"
#include "gear_dynamics/config/config.hpp"
#include "gear_dynamics/config/parameters.hpp"

namespace gd = gear_dynamics;
namespace fs = std::filesystem;

namespace {

const fs::path kConfigDir = GEAR_DYNAMICS_CONFIG_DIR;
const fs::path kSourceDir = kConfigDir.parent_path();

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Equal as configuration values: numbers by value, lists element by element, the rest as text.
bool same(const YAML::Node& a, const YAML::Node& b) {
  if (a.IsSequence() || b.IsSequence()) {
    if (!a.IsSequence() || !b.IsSequence() || a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!same(a[i], b[i])) return false;
    return true;
  }
  double x, y;
  if (gd::detail::as_number(a, x) && gd::detail::as_number(b, y)) return x == y;
  return a.IsScalar() && b.IsScalar() && a.Scalar() == b.Scalar();
}

const gd::SectionSpec& declared(const std::string& name) {
  static const std::vector<gd::SectionSpec> all = gd::parameter_sections();
  for (const gd::SectionSpec& s : all)
    if (s.name == name) return s;
  throw std::logic_error("no section " + name);
}

}  // namespace

TEST(Parameters, ShippedFilesHoldTheDeclaredKeysWithTheDeclaredDefaults) {
  const std::map<std::string, std::string> files = {{"gear_pair", "gear_pair.yaml"}, {"load", "load.yaml"},
                                                    {"run", "run.yaml"},             {"monte_carlo", "monte_carlo.yaml"},
                                                    {"simulator", "simulator.yaml"}, {"analysis", "aggregator.yaml"}};
  for (const auto& [section, file] : files) {
    const YAML::Node shipped = YAML::LoadFile((kConfigDir / file).string())[section];
    ASSERT_TRUE(shipped.IsMap()) << file;
    std::vector<std::string> keys, declared_keys;
    for (const auto& kv : shipped) keys.push_back(kv.first.as<std::string>());
    for (const gd::KeySpec& k : declared(section).keys) {
      if (k.omitted_at_default) continue;  // a non-default model's key: not shipped, optional
      declared_keys.push_back(k.name);
      EXPECT_TRUE(same(shipped[k.name], k.default_value))
          << section << "." << k.name << ": " << file << " holds " << gd::detail::show(shipped[k.name])
          << ", the declaration's default is " << gd::detail::show(k.default_value);
    }
    EXPECT_EQ(keys, declared_keys) << file << ": keys (in order) differ from the declaration";
  }
}

TEST(Parameters, AggregatorLaunchDefaultsAreTheDeclaredOnes) {
  const std::string launch = read_text(kSourceDir / "launch" / "aggregator.launch");
  const std::regex arg(R"re(<arg name="(\w+)" default="([^"]*)")re");
  int compared = 0;
  for (auto it = std::sregex_iterator(launch.begin(), launch.end(), arg); it != std::sregex_iterator(); ++it) {
    const gd::KeySpec* k = declared("aggregator").find((*it)[1].str());
    if (!k) continue;  // config, plot, output: the launch file's own arguments
    // "-" stands for the empty text (the launch file turns it into "").
    const std::string value = (*it)[2].str() == "-" ? "" : (*it)[2].str();
    EXPECT_TRUE(same(YAML::Node(value), k->default_value))
        << "aggregator.launch: " << k->name << " defaults to \"" << (*it)[2].str() << "\", the declaration to "
        << gd::detail::show(k->default_value);
    ++compared;
  }
  EXPECT_EQ(compared, 6);  // every optional key but plot_script (set from the plot argument)
}

TEST(Parameters, OptionalKeysLeftOutTakeTheirDefaults) {
  YAML::Node params = YAML::LoadFile((kConfigDir / "aggregator.yaml").string());
  params["folders"] = "/data/batch";
  const gd::AggregatorSettings s = gd::parse_aggregator_settings(params), defaults;
  EXPECT_EQ(s.folders, std::vector<std::string>{"/data/batch"});
  EXPECT_EQ(s.report_dir(), "/data/batch/report");
  const YAML::Node got = gd::aggregator_section().to_yaml(s), want = gd::aggregator_section().to_yaml(defaults);
  for (const gd::KeySpec& k : declared("aggregator").keys)
    if (!k.required) {
      EXPECT_TRUE(same(got[k.name], want[k.name])) << k.name;
    }
}

TEST(Parameters, SectionsRoundTripThroughTheirYaml) {
  const gd::ModelConfig model;
  EXPECT_EQ(gd::detail::show(gd::to_yaml(gd::parse_config(gd::to_yaml(model)))), gd::detail::show(gd::to_yaml(model)));
  gd::AggregatorSettings a;
  a.folders = {"/a", "/b"};
  a.wait_timeout = 12.5;
  YAML::Node params = gd::aggregator_section().to_yaml(a);
  params["analysis"] = gd::to_yaml(a.analysis)["analysis"];
  EXPECT_EQ(gd::detail::show(gd::aggregator_section().to_yaml(gd::parse_aggregator_settings(params))),
            gd::detail::show(gd::aggregator_section().to_yaml(a)));
}

// Every block "<!-- parameters: NAME -->" ... "<!-- /parameters -->" of README.md and doc/*.md
// holds the table gear_run --print-parameters NAME prints; once the docs carry such blocks, every
// section must have one.
TEST(Parameters, DocTablesAreTheGeneratedOnes) {
  std::vector<fs::path> files{kSourceDir / "README.md"};
  if (fs::is_directory(kSourceDir / "doc"))
    for (const auto& e : fs::directory_iterator(kSourceDir / "doc"))
      if (e.path().extension() == ".md") files.push_back(e.path());
  const std::string open = "<!-- parameters: ", close = "<!-- /parameters -->";
  std::map<std::string, int> blocks;
  for (const fs::path& file : files) {
    const std::string text = read_text(file);
    for (auto at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      const auto name_end = text.find(" -->", at);
      const std::string name = text.substr(at + open.size(), name_end - at - open.size());
      const auto body = text.find('\n', name_end) + 1, end = text.find(close, body);
      ASSERT_NE(end, std::string::npos) << file << ": the block " << name << " is not closed by " << close;
      const gd::SectionSpec* spec = nullptr;
      for (const gd::SectionSpec& s : gd::parameter_sections())
        if (s.name == name) spec = &declared(s.name);
      ASSERT_NE(spec, nullptr) << file << ": no section '" << name << "'";
      EXPECT_EQ(text.substr(body, end - body), gd::parameter_table(*spec))
          << file.filename() << ": the table of '" << name << "' differs from `gear_run --print-parameters " << name
          << "`; python3 scripts/update_parameter_docs.py rewrites the blocks";
      ++blocks[name];
    }
  }
  if (blocks.empty()) GTEST_SKIP() << "the docs carry no \"" << open << "NAME -->\" block yet";
  for (const gd::SectionSpec& s : gd::parameter_sections())
    EXPECT_GE(blocks[s.name], 1) << "no doc holds the table of '" << s.name << "' between \"" << open << s.name
                                 << " -->\" and \"" << close << "\"";
}
