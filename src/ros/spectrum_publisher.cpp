#include "gear_dynamics/ros/spectrum_publisher.hpp"

#include <utility>

#include "gear_dynamics/Spectrum.h"
#include "gear_dynamics/ros/conversions.hpp"

namespace gear_dynamics {

SpectrumPublisher::SpectrumPublisher(ros::NodeHandle& nh, const SpectrumSampling& sampling)
    : pub_(nh.advertise<Spectrum>("spectrum", 1, /*latch=*/true)),
      worker_(sampling, [this](LiveSpectrum& s) { publish(s); },
              [](const std::string& what) { ROS_ERROR_THROTTLE(10.0, "spectrum: %s", what.c_str()); }) {}

void SpectrumPublisher::publish(LiveSpectrum& s) {
  Spectrum m;
  m.header.stamp = sim_stamp(s.t);
  m.t = s.t;
  m.window_start = s.window_start;
  m.samples = s.samples;
  m.sample_steps = s.sample_steps;
  m.sample_rate = s.sample_rate;
  m.window = "hann";
  m.segment = static_cast<std::uint32_t>(s.delta.segment);
  m.overlap = s.delta.overlap;
  m.segments = static_cast<std::uint32_t>(s.delta.segments);
  m.resolution = s.delta.resolution;
  m.enbw = s.delta.enbw;
  m.mesh_frequency = s.mesh_frequency;
  m.frequency = std::move(s.delta.frequency);
  m.delta_psd = std::move(s.delta.density);
  m.mesh_force_psd = std::move(s.force.density);
  pub_.publish(m);
}

}  // namespace gear_dynamics
