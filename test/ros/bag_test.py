#!/usr/bin/python3
"""roslaunch gear_dynamics simulate.launch record:=true: the node's own bag, closed at t_end, holds
the messages it published (state, run_info, final_state, the scalars) under their absolute names,
and rosbag play publishes them again unchanged."""
import glob
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
from gear_dynamics.msg import GearState, RunInfo

from simtest import Collector, ends_at, last_run, services, wait_until

T_END = 0.05
TOPICS = ('/gear/state', '/gear/run_info')  # absolute, as the node writes them


def without_seq(msg):
    """A message as it goes into the bag, header.seq cleared: roscpp numbers each message on the
    wire per publisher, the in-process bag keeps the message as the node built it (seq 0)."""
    msg.header.seq = 0
    buff = io.BytesIO()
    msg.serialize(buff)
    return buff.getvalue()


class BagRoundTrip(unittest.TestCase):
    def test_record_and_play(self):
        folder = tempfile.mkdtemp(prefix='gear_bag_test_')
        self.addCleanup(shutil.rmtree, folder)
        launch = subprocess.Popen(
            ['roslaunch', 'gear_dynamics', 'simulate.launch', 'record:=true', 'record_dir:=' + folder,
             'paused:=true', 't_end:=%r' % T_END, 'real_time_factor:=0', 'output:=log'],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            state = Collector('/gear/state', GearState)
            info = Collector('/gear/run_info', RunInfo)
            final = Collector('/gear/final_state', GearState)
            state.wait_connected(30.0)
            srv = services('/gear/gear_simulator')
            srv['reset']()
            srv['unpause']()
            live = last_run(state.wait_for(ends_at(T_END), 30.0, 't_end'))
            live_info = info.wait_for(len, 10.0, 'run_info')[-1]
            live_final = final.wait_for(len, 10.0, 'final_state')[-1]
            # The node closes the run's bag at t_end.
            wait_until(lambda: glob.glob(os.path.join(folder, 'gear_*.bag')), 30.0, 'the closed bag')
        finally:
            os.killpg(launch.pid, signal.SIGINT)  # Ctrl-C
            launch.wait(timeout=30)

        bags = glob.glob(os.path.join(folder, 'gear_*.bag'))
        self.assertEqual(len(bags), 1, os.listdir(folder))  # closed cleanly: no .active left
        with rosbag.Bag(bags[0]) as bag:
            recorded = {t: [raw[1] for _, raw, _ in bag.read_messages(topics=[t], raw=True)]
                        for t in TOPICS + ('/gear/final_state', '/gear/delta')}
        # Byte for byte but header.seq: the run after the reset, the latest run_info, final_state.
        states = [GearState().deserialize(b) for b in recorded['/gear/state']]
        start = len(states) - len(last_run(states))
        self.assertEqual(recorded['/gear/state'][start:], [without_seq(m) for m in live])
        self.assertEqual(recorded['/gear/run_info'][-1], without_seq(live_info))
        self.assertEqual(recorded['/gear/final_state'], [without_seq(live_final)])
        self.assertEqual(live_final.t, live[-1].t)
        self.assertEqual(len(recorded['/gear/delta']), len(states))  # the scalar topics too

        # Play it back to other names; the node is gone, nothing else publishes there.
        played = {t: Collector('/played' + t, rospy.AnyMsg) for t in TOPICS}
        subprocess.run(['rosbag', 'play', '--wait-for-subscribers', '--topics'] + list(TOPICS) +
                       ['--bags=' + bags[0]] + ['%s:=/played%s' % (t, t) for t in TOPICS],
                       check=True, timeout=60, stdout=subprocess.DEVNULL)
        for t in TOPICS:
            n = len(recorded[t])
            got = played[t].wait_for(lambda m: len(m) >= n, 10.0, 'all played messages')
            self.assertEqual([m._buff for m in got], recorded[t])

if __name__ == '__main__':
    rospy.init_node('bag_test')
    rostest.rosrun('gear_dynamics', 'bag_round_trip', BagRoundTrip, sys.argv)
