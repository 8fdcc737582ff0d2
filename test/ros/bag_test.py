#!/usr/bin/python3
"""roslaunch gear_dynamics simulate.launch record:=true, stopped with SIGINT: the bag holds the
messages the node published (state, run_info), and rosbag play publishes them again unchanged."""
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
import xmlrpc.client

import rosbag
import rosgraph
import rospy
import rostest
from gear_dynamics.msg import GearState, RunInfo

from simtest import Collector, ends_at, last_run, services, wait_until

T_END = 0.05
TOPICS = ('state', 'run_info')  # relative, as simulate.launch records them (namespace-proof)


def wire(msg):
    """A message as it goes over the wire and into a bag."""
    buff = io.BytesIO()
    msg.serialize(buff)
    return buff.getvalue()


def outbound_connections(node, topic):
    """How many subscribers `node` is connected to on `topic` (from its own bus info)."""
    uri = rosgraph.Master('/bag_test').lookupNode(node)
    _, _, info = xmlrpc.client.ServerProxy(uri).getBusInfo('/bag_test')
    return sum(1 for c in info if c[2] == 'o' and c[4] == topic)


class BagRoundTrip(unittest.TestCase):
    def test_record_and_play(self):
        folder = tempfile.mkdtemp(prefix='gear_bag_test_')
        self.addCleanup(shutil.rmtree, folder)
        launch = subprocess.Popen(
            ['roslaunch', 'gear_dynamics', 'simulate.launch', 'record:=true', 'record_dir:=' + folder,
             'paused:=true', 't_end:=%r' % T_END, 'real_time_factor:=0', 'output:=log'],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            state = Collector('/state', GearState)
            info = Collector('/run_info', RunInfo)
            state.wait_connected(30.0)
            # rosbag and this test both listen before the run starts.
            wait_until(lambda: outbound_connections('/gear_simulator', '/state') == 2
                       and outbound_connections('/gear_simulator', '/run_info') == 2, 30.0, 'rosbag record')
            srv = services('/gear_simulator')
            srv['reset']()
            srv['unpause']()
            live = last_run(state.wait_for(ends_at(T_END), 30.0, 't_end'))
            live_info = info.wait_for(len, 10.0, 'run_info')[-1]
            time.sleep(0.5)  # rosbag writes what is on its way
        finally:
            os.killpg(launch.pid, signal.SIGINT)  # Ctrl-C
            launch.wait(timeout=30)

        bags = glob.glob(os.path.join(folder, 'gear_simulator_*.bag'))
        self.assertEqual(len(bags), 1, os.listdir(folder))  # closed cleanly: no .active left
        with rosbag.Bag(bags[0]) as bag:
            recorded = {t: [raw[1] for _, raw, _ in bag.read_messages(topics=[t], raw=True)] for t in TOPICS}
        # Byte for byte (header.seq included): the run after the reset, and the latest run_info.
        states = [GearState().deserialize(b) for b in recorded['state']]
        start = len(states) - len(last_run(states))
        self.assertEqual(recorded['state'][start:], [wire(m) for m in live])
        self.assertEqual(recorded['run_info'][-1], wire(live_info))

        # Play it back to other names; the node is gone, nothing else publishes there.
        played = {t: Collector('/played/' + t, rospy.AnyMsg) for t in TOPICS}
        subprocess.run(['rosbag', 'play', '--wait-for-subscribers', '--topics'] + list(TOPICS) +
                       ['--bags=' + bags[0]] + ['%s:=/played/%s' % (t, t) for t in TOPICS],
                       check=True, timeout=60, stdout=subprocess.DEVNULL)
        for t in TOPICS:
            n = len(recorded[t])
            got = played[t].wait_for(lambda m: len(m) >= n, 10.0, 'all played messages')
            self.assertEqual([m._buff for m in got], recorded[t])

if __name__ == '__main__':
    rospy.init_node('bag_test')
    rostest.rosrun('gear_dynamics', 'bag_round_trip', BagRoundTrip, sys.argv)
