#!/usr/bin/python3
"""end_launch: ends the roslaunch that started it, as Ctrl-C would, once every node named in ~watch
(a list of node names relative to this node's namespace) has ended, so that a launch whose work is
done (gear_monte_carlo, gear_aggregator with exit_when_done) ends cleanly. roslaunch 1.15 prints its
red 'REQUIRED process [...] has died!' banner for every required node that ends, successfully or
not, and without a required node it never ends by itself (its own rosout stays); with this helper
the watched nodes are not required, a success ends quietly and a failure still shows in red through
roslaunch's own 'process has died [exit code N]' line. It acts only when its parent process is
roslaunch (under rostest, which runs the launch in-process, it does nothing)."""
import os
import signal

# A signal ends this node at once, whenever it comes: the node holds nothing to clean up, and
# rospy's handler, run while init_node holds rospy's locks, deadlocks (roslaunch then waits 15 s
# and escalates to SIGKILL).
signal.signal(signal.SIGINT, signal.SIG_DFL)
signal.signal(signal.SIGTERM, signal.SIG_DFL)

import time  # noqa: E402
import xmlrpc.client  # noqa: E402

import rosgraph  # noqa: E402
import rospy  # noqa: E402


def parent_is_roslaunch():
    try:
        with open('/proc/%d/cmdline' % os.getppid(), 'rb') as f:
            argv = f.read().split(b'\0')
    except OSError:
        return False
    return any(os.path.basename(a) == b'roslaunch' for a in argv[:2])


def parent_server():
    """The XML-RPC server of the roslaunch whose process is our parent. A master kept up between
    launches keeps every earlier roslaunch's entry in /roslaunch/uris (roslaunch never removes it):
    an entry that does not answer, or answers with another pid, is someone else's."""
    uris = rosgraph.Master(rospy.get_name()).getParam('/roslaunch/uris')
    for uri in uris.values():
        server = xmlrpc.client.ServerProxy(uri)
        try:
            code, _, pid = server.get_pid()
        except (OSError, xmlrpc.client.Error):
            continue
        if code == 1 and pid == os.getppid():
            return server
    return None


def process_prefix(name):
    """roslaunch's process name of node `name` (e.g. /gear/gear_simulator -> gear-gear_simulator-N)."""
    return rospy.resolve_name(name).strip('/').replace('/', '-') + '-'


def main():
    rospy.init_node('end_launch', disable_signals=True)
    watch = [process_prefix(n) for n in rospy.get_param('~watch', [])]
    if not watch or not parent_is_roslaunch():
        rospy.loginfo('end_launch: not under roslaunch or nothing to watch; idle')
        rospy.spin()
        return
    server = None
    while not rospy.is_shutdown():
        time.sleep(0.2)
        server = server or parent_server()
        if server is None:
            continue
        code, _, (active, dead) = server.list_processes()
        alive = [p for p, _ in active if any(p.startswith(w) for w in watch)]
        ended = [p for p, _ in dead if any(p.startswith(w) for w in watch)]
        if not alive and len(ended) >= len(watch):
            rospy.loginfo('end_launch: %s ended; ending the launch', ', '.join(ended))
            os.kill(os.getppid(), signal.SIGINT)  # roslaunch answers with SIGINT to this node too
            while True:
                time.sleep(1.0)


if __name__ == '__main__':
    main()
