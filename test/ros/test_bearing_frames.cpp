// The frames of the bearing wrenches (make_bearing_frames, doc/gear_simulator.md §3.4) against the
// geometry of doc/model.md §11 written out here: from the pinion's centre the wheel's is
// (Rb1 + Rb2) e_x + lp e_y, so the frame turned by the transform must carry that vector onto the
// wheel_bearing's translation, along gear_pair's x. With profile shifts alpha_w differs from
// pressure_angle, which is why the node computes the frames and the URDF does not hold them.
#include <gtest/gtest.h>

#include <cmath>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/ros/conversions.hpp"

namespace gd = gear_dynamics;

namespace {

void expect_frames_of(const gd::GearInputs& in) {
  const gd::GearPair g = gd::derive(in);
  const auto frames = gd::make_bearing_frames(g, ros::Time(1.0));
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].header.frame_id, "gear_pair");
  EXPECT_EQ(frames[0].child_frame_id, "pinion_bearing");
  EXPECT_EQ(frames[1].child_frame_id, "wheel_bearing");
  for (const auto& f : frames) {
    const auto& q = f.transform.rotation;
    // A turn about z only, by -alpha_w.
    EXPECT_EQ(q.x, 0.0);
    EXPECT_EQ(q.y, 0.0);
    EXPECT_NEAR(2.0 * std::atan2(q.z, q.w), -g.operating_pressure_angle, 1e-15);
    EXPECT_EQ(f.transform.translation.y, 0.0);
    EXPECT_EQ(f.transform.translation.z, 0.0);
  }
  EXPECT_EQ(frames[0].transform.translation.x, 0.0);
  // (Rb1 + Rb2, lp) in the bearing frame, turned into gear_pair's by the quaternion's yaw.
  const double yaw = 2.0 * std::atan2(frames[1].transform.rotation.z, frames[1].transform.rotation.w);
  const double ex = g.base_radius1 + g.base_radius2, ey = g.line_of_centres_length;
  const double x = std::cos(yaw) * ex - std::sin(yaw) * ey, y = std::sin(yaw) * ex + std::cos(yaw) * ey;
  EXPECT_NEAR(x, frames[1].transform.translation.x, 1e-15);  // a few ulps of 0.1 m
  EXPECT_NEAR(y, 0.0, 1e-15);
}

}  // namespace

TEST(BearingFrames, DefaultGearIsTheCentreLineTurnedByMinusTwentyDegrees) {
  const gd::GearInputs in;
  expect_frames_of(in);
  EXPECT_NEAR(gd::derive(in).operating_pressure_angle, 20.0 * M_PI / 180.0, 1e-15);
}

TEST(BearingFrames, FollowThePressureAngle) {
  gd::GearInputs in;
  in.pressure_angle = 25.0 * M_PI / 180.0;
  expect_frames_of(in);
}

TEST(BearingFrames, FollowTheWorkingPressureAngleOfShiftedProfiles) {
  gd::GearInputs in;
  in.profile_shift1 = 0.3;
  in.profile_shift2 = 0.2;
  const gd::GearPair g = gd::derive(in);
  EXPECT_GT(g.operating_pressure_angle, in.pressure_angle + 0.01);  // x1 + x2 > 0 opens the centre distance
  expect_frames_of(in);
}
