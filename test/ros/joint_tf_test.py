#!/usr/bin/python3
"""simulate.launch tf:=true, headless: gear_simulator's NS/joint_states through robot_state_publisher
and urdf/gear_pair.urdf.

- joint_states: names pinion_joint, wheel_joint; theta1 = Omega t (phi0 = 0), theta2 =
  (Rb1 theta1 - delta)/Rb2 with delta of the state at the same stamp, and their rates;
- TF at a joint state's stamp: gear_pair -> pinion turns by theta1 about +z, gear_pair -> wheel by
  theta2 about -z, 0.1 m away (r1 + r2), and pinion -> wheel follows both.
"""
import math
import sys
import threading
import unittest

import rospy
import rostest
import tf2_ros

from gear_dynamics.msg import GearState
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage

R1, R2, ALPHA0 = 0.02, 0.08, 0.3490658503988659  # config/gear_pair.yaml
RB1, RB2 = R1 * math.cos(ALPHA0), R2 * math.cos(ALPHA0)
OMEGA = 104.71975511965977


def yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def same_angle(a, b):
    return abs(math.remainder(a - b, 2.0 * math.pi))


class JointTf(unittest.TestCase):
    def setUp(self):
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

    def test_joint_states_and_tf_follow_the_states(self):
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
            self.assertAlmostEqual(theta1, OMEGA * s.t, delta=1e-9 * max(1.0, theta1))
            self.assertAlmostEqual(theta2, (RB1 * theta1 - s.delta) / RB2, delta=1e-9 * max(1.0, theta2))
            self.assertEqual(j.velocity[0], OMEGA)
            self.assertAlmostEqual(j.velocity[1], (RB1 * OMEGA - s.delta_dot) / RB2, delta=1e-9)
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
            self.assertAlmostEqual(math.hypot(t.x, t.y), R1 + R2, places=9)
            b = between.transform.translation  # the wheel's axis seen from the turning pinion
            self.assertLess(same_angle(math.atan2(b.y, b.x), -theta1), tolerance)
            checked += 1
        self.assertEqual(checked, 10)


if __name__ == '__main__':
    rospy.init_node('joint_tf_test')
    rostest.rosrun('gear_dynamics', 'joint_tf', JointTf, sys.argv)
