#!/usr/bin/python3
"""simulate.launch tf:=true with joint_tf_gear.yaml (a gear other than the default), headless:
gear_simulator's NS/joint_states through robot_state_publisher and the URDF of the configured gear.

- robot_description: the pinion and the wheel drawn at the working pitch radii and the face width,
  the wheel's axis at the working centre distance, all computed here from the run's configuration
  (alpha_w solved by bisection on the involute function);
- joint_states: names pinion_joint, wheel_joint; theta1 = Omega t (phi0 = 0), theta2 =
  (Rb1 theta1 - delta)/Rb2 with delta of the state at the same stamp, and their rates;
- TF at a joint state's stamp: gear_pair -> pinion turns by theta1 about +z, gear_pair -> wheel by
  theta2 about -z, the working centre distance away, and pinion -> wheel follows both.
"""
import math
import sys
import threading
import unittest
import xml.etree.ElementTree as ET

import rospy
import rostest
import tf2_ros
import yaml

from gear_dynamics.msg import GearState, RunInfo
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage


class Gear:
    """The drawing's and the joints' quantities of the gear_pair section (doc/model.md §3)."""

    def __init__(self, g):
        alpha0 = g['pressure_angle']
        self.rb1 = g['pinion_pitch_radius'] * math.cos(alpha0)
        self.rb2 = g['gear_pitch_radius'] * math.cos(alpha0)
        self.omega = g['pinion_speed']
        self.face_width = g['face_width']

        def inv(a):
            return math.tan(a) - a
        target = inv(alpha0) + 2.0 * math.tan(alpha0) * (g.get('profile_shift1', 0.0) + g.get('profile_shift2', 0.0)) / (
            g['pinion_teeth'] + g['gear_teeth'])
        lo, hi = 0.01, 1.5
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if inv(mid) < target else (lo, mid)
        alpha_w = 0.5 * (lo + hi)
        self.rw1, self.rw2 = self.rb1 / math.cos(alpha_w), self.rb2 / math.cos(alpha_w)
        self.centre_distance = self.rw1 + self.rw2
        self.reference_distance = g['pinion_pitch_radius'] + g['gear_pitch_radius']


def yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def same_angle(a, b):
    return abs(math.remainder(a - b, 2.0 * math.pi))


class JointTf(unittest.TestCase):
    def setUp(self):
        info = rospy.wait_for_message('/gear/run_info', RunInfo, timeout=30.0)
        self.gear = Gear(yaml.safe_load(info.parameters_yaml)['gear_pair'])
        self.lock = threading.Lock()
        self.states, self.joints = {}, []
        self.subs = [rospy.Subscriber('/gear/state', GearState, self.on_state, queue_size=None),
                     rospy.Subscriber('/gear/joint_states', JointState, self.on_joints, queue_size=None)]
        # The stamps robot_state_publisher sent a transform for: under load it can miss a joint state
        # (its subscriber queue), and TF would then interpolate across the gap.
        self.tf_stamps = {'pinion': set(), 'wheel': set()}
        self.subs.append(rospy.Subscriber('/tf', TFMessage, self.on_tf, queue_size=None))
        self.tf = tf2_ros.Buffer(cache_time=rospy.Duration(30.0))
        self.listener = tf2_ros.TransformListener(self.tf)

    def on_state(self, m):
        with self.lock:
            self.states[m.header.stamp] = m

    def on_tf(self, m):
        with self.lock:
            for t in m.transforms:
                if t.child_frame_id in self.tf_stamps:
                    self.tf_stamps[t.child_frame_id].add(t.header.stamp)

    def on_joints(self, m):
        with self.lock:
            self.joints.append(m)

    def test_robot_description_is_the_configured_gear(self):
        g = self.gear
        self.assertGreater(g.centre_distance, g.reference_distance + 1e-4)  # not the reference gear
        robot = ET.fromstring(rospy.get_param('/gear/robot_description'))
        for link, radius in (('pinion', g.rw1), ('wheel', g.rw2)):
            cylinder = robot.find("link[@name='%s']/visual/geometry/cylinder" % link)
            self.assertAlmostEqual(float(cylinder.get('radius')), radius, delta=1e-12, msg=link)
            self.assertAlmostEqual(float(cylinder.get('length')), g.face_width, delta=1e-12, msg=link)
        origin = robot.find("joint[@name='wheel_joint']/origin").get('xyz').split()
        self.assertAlmostEqual(float(origin[0]), g.centre_distance, delta=1e-12)
        self.assertEqual([float(v) for v in origin[1:]], [0.0, 0.0])

    def test_joint_states_and_tf_follow_the_states(self):
        g = self.gear
        deadline = rospy.Time.now() + rospy.Duration(5.0)  # simulated time (real_time_factor 1)
        while rospy.Time.now() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        with self.lock:
            joints, states = list(self.joints), dict(self.states)
        rospy.sleep(1.0)  # the transforms of those joint states arrive after them
        with self.lock:
            sent = self.tf_stamps['pinion'] & self.tf_stamps['wheel']
        self.assertGreater(len(joints), 1000)
        matched = 0
        for j in joints:
            self.assertEqual(j.name, ['pinion_joint', 'wheel_joint'])
            s = states.get(j.header.stamp)
            if s is None:
                continue
            matched += 1
            theta1, theta2 = j.position
            self.assertAlmostEqual(theta1, g.omega * s.t, delta=1e-9 * max(1.0, theta1))
            self.assertAlmostEqual(theta2, (g.rb1 * theta1 - s.delta) / g.rb2, delta=1e-9 * max(1.0, theta2))
            self.assertEqual(j.velocity[0], g.omega)
            self.assertAlmostEqual(j.velocity[1], (g.rb1 * g.omega - s.delta_dot) / g.rb2, delta=1e-9)
        self.assertGreater(matched, 1000)

        # TF goes through KDL's rotation matrices and back to quaternions: 2e-6 rad was seen at
        # angles of about 100 rad. One publish period turns the wheel by 0.026 rad.
        tolerance = 1e-5
        checked = 0
        # robot_state_publisher sends one joint state in 20 (its 50 Hz publish_frequency); TF between
        # two of them interpolates, so only the sent stamps are compared (recent: inside the buffer).
        recent = [j for j in joints[-1000:] if j.header.stamp in sent]
        self.assertGreaterEqual(len(recent), 10)
        for j in recent[-10:]:
            theta1, theta2 = j.position
            pinion = self.tf.lookup_transform('gear_pair', 'pinion', j.header.stamp, rospy.Duration(2.0))
            wheel = self.tf.lookup_transform('gear_pair', 'wheel', j.header.stamp, rospy.Duration(2.0))
            between = self.tf.lookup_transform('pinion', 'wheel', j.header.stamp, rospy.Duration(2.0))
            self.assertLess(same_angle(yaw(pinion.transform.rotation), theta1), tolerance)
            self.assertLess(same_angle(yaw(wheel.transform.rotation), -theta2), tolerance)
            self.assertLess(same_angle(yaw(between.transform.rotation), -theta2 - theta1), tolerance)
            t = wheel.transform.translation
            self.assertAlmostEqual(math.hypot(t.x, t.y), g.centre_distance, places=9)
            b = between.transform.translation  # the wheel's axis seen from the turning pinion
            self.assertLess(same_angle(math.atan2(b.y, b.x), -theta1), tolerance)
            checked += 1
        self.assertEqual(checked, 10)


if __name__ == '__main__':
    rospy.init_node('joint_tf_test')
    rostest.rosrun('gear_dynamics', 'joint_tf', JointTf, sys.argv)
