#!/usr/bin/python3
"""A plain integral controller that holds the gear's load Phi at a setpoint through the simulator's
load input: at every state it sends load_command u <- u + gain (setpoint - Phi) (std_msgs/Float64,
m/s^2). With simulator.load_input external_plus_noise the plant's Phi is u plus the load SDE's own
increments, which the loop cancels. Parameters: ~setpoint [m/s^2], ~gain [-], ~ns (the simulator's)."""
import rospy
from std_msgs.msg import Float64
from gear_dynamics.msg import GearState


def main():
    rospy.init_node('load_controller')
    setpoint = rospy.get_param('~setpoint', 30.0)
    gain = rospy.get_param('~gain', 0.5)
    ns = rospy.get_param('~ns', '/gear').rstrip('/')
    pub = rospy.Publisher(ns + '/load_command', Float64, queue_size=10, tcp_nodelay=True)
    u = [setpoint]

    def on_state(m):
        u[0] += gain * (setpoint - m.phi)
        pub.publish(Float64(u[0]))

    rospy.Subscriber(ns + '/state', GearState, on_state, queue_size=10, tcp_nodelay=True)
    rospy.spin()


if __name__ == '__main__':
    main()
