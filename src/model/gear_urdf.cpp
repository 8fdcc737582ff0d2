#include "gear_dynamics/model/gear_urdf.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace gear_dynamics {

namespace {

// The shortest text that reads back as the same double: 0.1, not 0.10000000000000001.
std::string number(double x) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, x).ptr;
  return std::string(text, end);
}

// Six digits, for the comment.
std::string rounded(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", x);
  return text;
}

// A gear's link: its cylinder and the mark on its rim, at x = mark_x on the +z face (rim marks at
// 1.5 modules inside the pitch circle, 3 x 1.5 x 1 modules: the drawing's size, whatever the gear).
void gear_link(std::ostream& out, const char* name, const char* material, double radius, double mark_x,
               double face_width, double module) {
  out << "  <link name=\"" << name << "\">\n"
      << "    <visual>\n"
      << "      <geometry><cylinder radius=\"" << number(radius) << "\" length=\"" << number(face_width)
      << "\"/></geometry>\n"
      << "      <material name=\"" << material << "\"/>\n"
      << "    </visual>\n"
      << "    <visual>\n"
      << "      <origin xyz=\"" << number(mark_x) << " 0 " << number(0.5 * face_width + 0.5 * module) << "\"/>\n"
      << "      <geometry><box size=\"" << number(3.0 * module) << ' ' << number(1.5 * module) << ' '
      << number(module) << "\"/></geometry>\n"
      << "      <material name=\"mark\"/>\n"
      << "    </visual>\n"
      << "  </link>\n\n";
}

}  // namespace

double working_pitch_radius1(const GearPair& gear) {
  return gear.in.pinion_pitch_radius * (std::cos(gear.in.pressure_angle) / std::cos(gear.operating_pressure_angle));
}

double working_pitch_radius2(const GearPair& gear) {
  return gear.in.gear_pitch_radius * (std::cos(gear.in.pressure_angle) / std::cos(gear.operating_pressure_angle));
}

std::string gear_pair_urdf(const GearPair& gear) {
  const double r1 = working_pitch_radius1(gear), r2 = working_pitch_radius2(gear);
  const double m = gear.module, width = gear.in.face_width;
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<!-- The configured gear pair (doc/gear_simulator.md, section 3.3): working pitch circles r1 = " << rounded(r1)
      << " m and r2 = " << rounded(r2) << " m,\n"
      << "     axes the working centre distance " << rounded(r1 + r2) << " m apart, face width " << rounded(width)
      << " m; a mark on each rim shows the rotation.\n"
      << "     pinion_joint: theta1 about +z; wheel_joint: theta2 about -z, the way the pinion drives it.\n"
      << "     The bearings model's frames are gear_simulator's own, on /tf_static (doc/gear_simulator.md). -->\n"
      << "<robot name=\"gear_pair\">\n"
      << "  <material name=\"pinion_grey\"><color rgba=\"0.55 0.6 0.65 1\"/></material>\n"
      << "  <material name=\"wheel_brass\"><color rgba=\"0.8 0.65 0.3 1\"/></material>\n"
      << "  <material name=\"mark\"><color rgba=\"0.8 0.1 0.1 1\"/></material>\n\n"
      << "  <link name=\"gear_pair\"/>\n\n";
  // The marks face each other at theta = 0: the pinion's towards +x, the wheel's towards -x.
  gear_link(out, "pinion", "pinion_grey", r1, r1 - 1.5 * m, width, m);
  gear_link(out, "wheel", "wheel_brass", r2, -(r2 - 1.5 * m), width, m);
  out << "  <joint name=\"pinion_joint\" type=\"continuous\">\n"
      << "    <parent link=\"gear_pair\"/>\n"
      << "    <child link=\"pinion\"/>\n"
      << "    <origin xyz=\"0 0 0\"/>\n"
      << "    <axis xyz=\"0 0 1\"/>\n"
      << "  </joint>\n\n"
      << "  <joint name=\"wheel_joint\" type=\"continuous\">\n"
      << "    <parent link=\"gear_pair\"/>\n"
      << "    <child link=\"wheel\"/>\n"
      << "    <origin xyz=\"" << number(r1 + r2) << " 0 0\"/>\n"
      << "    <axis xyz=\"0 0 -1\"/>\n"
      << "  </joint>\n"
      << "</robot>\n";
  return out.str();
}

}  // namespace gear_dynamics
