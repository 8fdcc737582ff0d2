// The URDF of the configured gear pair (gear_pair_urdf), parsed by urdfdom (the parser
// robot_state_publisher uses): its links, joints and sizes against the gear computed here, the
// working pressure angle solved independently (bisection on the involute function).
#include <gtest/gtest.h>

#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <memory>
#include <string>

#include "gear_dynamics/model/gear_pair.hpp"
#include "gear_dynamics/model/gear_urdf.hpp"

namespace gd = gear_dynamics;

namespace {

// alpha_w from inv(alpha_w) = inv(alpha0) + 2 tan(alpha0) (x1 + x2) / (Z1 + Z2), by bisection.
double working_pressure_angle(const gd::GearInputs& in) {
  const auto inv = [](double a) { return std::tan(a) - a; };
  const double target = inv(in.pressure_angle) + 2.0 * std::tan(in.pressure_angle) *
                                                     (in.profile_shift1 + in.profile_shift2) /
                                                     (in.pinion_teeth + in.gear_teeth);
  double lo = 0.01, hi = 1.5;
  for (int i = 0; i < 200; ++i) (inv(0.5 * (lo + hi)) < target ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

// What the drawing of `in` must show, from the inputs alone.
struct Expected {
  double r1, r2, centre_distance, face_width, module;
};
Expected expected(const gd::GearInputs& in) {
  const double scale = std::cos(in.pressure_angle) / std::cos(working_pressure_angle(in));
  const double r1 = in.pinion_pitch_radius * scale, r2 = in.gear_pitch_radius * scale;
  return {r1, r2, r1 + r2, in.face_width, 2.0 * in.pinion_pitch_radius / in.pinion_teeth};
}

const urdf::Cylinder& cylinder(const urdf::Link& link) {
  EXPECT_EQ(link.visual_array.size(), 2u) << link.name;
  const auto* c = dynamic_cast<const urdf::Cylinder*>(link.visual_array.at(0)->geometry.get());
  if (c == nullptr) throw std::runtime_error(link.name + ": the first visual is not a cylinder");
  return *c;
}

void expect_drawing(const gd::GearInputs& in) {
  const Expected e = expected(in);
  const std::string text = gd::gear_pair_urdf(gd::derive(in));
  // Well-formed XML, which tinyxml does not insist on: "--" only to open and close a comment.
  for (std::size_t at = text.find("<!--"); at != std::string::npos; at = text.find("<!--", at + 1)) {
    const std::size_t end = text.find("-->", at + 4);
    ASSERT_NE(end, std::string::npos);
    EXPECT_EQ(text.substr(at + 4, end - at - 4).find("--"), std::string::npos) << text.substr(at, end - at);
  }
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
  ASSERT_TRUE(model) << text;
  EXPECT_EQ(model->getName(), "gear_pair");
  ASSERT_TRUE(model->getRoot());
  EXPECT_EQ(model->getRoot()->name, "gear_pair");
  const double tol = 1e-12;

  const struct {
    const char* link;
    const char* joint;
    double radius, axis_z, origin_x, mark_x;
  } gears[] = {{"pinion", "pinion_joint", e.r1, 1.0, 0.0, e.r1 - 1.5 * e.module},
               {"wheel", "wheel_joint", e.r2, -1.0, e.centre_distance, -(e.r2 - 1.5 * e.module)}};
  for (const auto& g : gears) {
    SCOPED_TRACE(g.link);
    const urdf::LinkConstSharedPtr link = model->getLink(g.link);
    const urdf::JointConstSharedPtr joint = model->getJoint(g.joint);
    ASSERT_TRUE(link);
    ASSERT_TRUE(joint);
    EXPECT_EQ(joint->type, urdf::Joint::CONTINUOUS);
    EXPECT_EQ(joint->parent_link_name, "gear_pair");
    EXPECT_EQ(joint->child_link_name, g.link);
    EXPECT_EQ(joint->axis.x, 0.0);
    EXPECT_EQ(joint->axis.y, 0.0);
    EXPECT_EQ(joint->axis.z, g.axis_z);
    const urdf::Pose& at = joint->parent_to_joint_origin_transform;
    EXPECT_NEAR(at.position.x, g.origin_x, tol);
    EXPECT_EQ(at.position.y, 0.0);
    EXPECT_EQ(at.position.z, 0.0);
    const urdf::Cylinder& c = cylinder(*link);
    EXPECT_NEAR(c.radius, g.radius, tol);
    EXPECT_NEAR(c.length, e.face_width, tol);
    // The mark: on the +z face, reaching out to the rim, a module thick.
    const urdf::Visual& mark = *link->visual_array.at(1);
    const auto* box = dynamic_cast<const urdf::Box*>(mark.geometry.get());
    ASSERT_NE(box, nullptr);
    EXPECT_NEAR(box->dim.z, e.module, tol);
    EXPECT_NEAR(mark.origin.position.x, g.mark_x, tol);
    EXPECT_NEAR(mark.origin.position.z, 0.5 * (e.face_width + e.module), tol);
    EXPECT_NEAR(std::abs(mark.origin.position.x) + 0.5 * box->dim.x, g.radius, tol);
  }
}

}  // namespace

TEST(GearUrdf, DefaultGearIsTheConfiguredOne) {
  // Unshifted: the reference pitch circles, 0.1 m apart, printed as the configuration's decimals.
  const gd::GearInputs in;
  expect_drawing(in);
  const std::string text = gd::gear_pair_urdf(gd::derive(in));
  EXPECT_NE(text.find("<cylinder radius=\"0.02\" length=\"0.01\"/>"), std::string::npos) << text;
  EXPECT_NE(text.find("<cylinder radius=\"0.08\" length=\"0.01\"/>"), std::string::npos) << text;
  EXPECT_NE(text.find("<origin xyz=\"0.1 0 0\"/>"), std::string::npos) << text;
}

TEST(GearUrdf, AnotherGearWithShiftedProfiles) {
  // m = 3 mm, Z = 17/43, 25 deg, x1 + x2 = 0.4: alpha_w > alpha0, the axes beyond r1 + r2.
  gd::GearInputs in;
  in.pinion_teeth = 17;
  in.gear_teeth = 43;
  in.pinion_pitch_radius = 0.5 * 0.003 * 17;
  in.gear_pitch_radius = 0.5 * 0.003 * 43;
  in.pressure_angle = 25.0 * M_PI / 180.0;
  in.face_width = 0.025;
  in.profile_shift1 = 0.3;
  in.profile_shift2 = 0.1;
  expect_drawing(in);
  const Expected e = expected(in);
  EXPECT_GT(e.centre_distance, in.pinion_pitch_radius + in.gear_pitch_radius + 0.3 * 0.003);
  // The drawing's centre distance is the one of the bearing frames (a_w = (Rb1 + Rb2)/cos(alpha_w)).
  const gd::GearPair g = gd::derive(in);
  EXPECT_NEAR(gd::working_pitch_radius1(g) + gd::working_pitch_radius2(g),
              (g.base_radius1 + g.base_radius2) / std::cos(g.operating_pressure_angle), 1e-15);
}
