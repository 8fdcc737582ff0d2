// The analysis settings: their YAML round trip and refusals that name the key.
#include <gtest/gtest.h>

#include <string>

#include "gear_dynamics/config/analysis_settings.hpp"
#include "gear_dynamics/config/config.hpp"

namespace gd = gear_dynamics;

TEST(AnalysisSettings, RoundTripAndErrorsNameTheKey) {
  gd::AnalysisSettings s;
  s.confidence = 0.9;
  s.delta_interval = {4.1e-5, 5.0e-5};
  s.joint_times = {0.33, 0.4};
  const gd::AnalysisSettings back = gd::parse_analysis_settings(gd::to_yaml(s));
  EXPECT_EQ(back.confidence, 0.9);
  EXPECT_EQ(back.delta_interval.lo, 4.1e-5);
  EXPECT_EQ(back.joint_times, s.joint_times);
  EXPECT_EQ(back.delta_dot_bins.width, s.delta_dot_bins.width);

  const auto error_of = [](const std::string& text) {
    try {
      gd::parse_analysis_settings(YAML::Load(text));
    } catch (const gd::ConfigError& ex) {
      return std::string(ex.what());
    }
    return std::string("no error");
  };
  YAML::Node good = gd::to_yaml(gd::AnalysisSettings{});
  const auto with = [&](const char* key, const char* value) {
    YAML::Node n = YAML::Clone(good);
    n["analysis"][key] = YAML::Load(value);
    YAML::Emitter e;
    e << n;
    return std::string(e.c_str());
  };
  EXPECT_NE(error_of(with("confidence", "1.5")).find("analysis.confidence = 1.5 is out of range; allowed (0, 1)"),
            std::string::npos);
  EXPECT_NE(error_of(with("delta_interval", "[5.5e-5, 4.0e-5]")).find("analysis.delta_interval"), std::string::npos);
  EXPECT_NE(error_of(with("delta_bins", "[3.0e-5, 6.0e-5, 7.0e-6]")).find("analysis.delta_bins"), std::string::npos);
  EXPECT_NE(error_of(with("joint_times", "[0.3, abc]")).find("analysis.joint_times"), std::string::npos);
  EXPECT_NE(error_of(with("delta_bin", "[0, 1, 1]")).find("analysis.delta_bin is not a known key"), std::string::npos);
  EXPECT_NE(error_of("other: 1").find("missing section 'analysis'"), std::string::npos);
}
