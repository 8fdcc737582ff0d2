#!/usr/bin/python3
"""launch/remote_simulator.launch with the machine address localhost, both ways roslaunch starts a
<machine>'s nodes:

  local_machine  user empty: localhost is this machine, roslaunch starts gear_simulator itself;
  ssh_machine    roslaunch's remote path: an sshd of the test's own on a free port of 127.0.0.1
                 (host key, authorized key and config in a temporary folder, root login by key
                 only), roslaunch with user:=root, ssh_port:=that port and a HOME of the test's own
                 (known_hosts, key) run under another user name (USER/LOGNAME; roslaunch compares
                 the machine's user with getpass.getuser() and takes a local address with another
                 user as remote). The node must run under sshd, started by scripts/remote_env.sh.

Each: the node registers, one run of t_end is published on /gear/state and the launch stops on SIGINT.
ssh_machine is skipped (reason printed) only where sshd is not installed (scripts/test.sh installs
openssh-server). Nothing the test starts is left running.
usage: remote_test.py [JUNIT.xml]"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET
import xmlrpc.client

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "test", "faults"))
sys.path.insert(0, os.path.join(REPO, "test", "ros"))
import faultlib as fl  # noqa: E402

T_END = 0.05
SSHD = "/usr/sbin/sshd"


def junit(path, cases):
    if not path:
        return
    suite = ET.Element("testsuite", name="remote", tests=str(len(cases)), errors="0",
                       failures=str(sum(c[1] == "FAILED" for c in cases)),
                       skipped=str(sum(c[1] == "skipped" for c in cases)))
    for name, status, message, seconds in cases:
        tc = ET.SubElement(suite, "testcase", classname="remote.remote_simulator", name=name, time="%.3f" % seconds)
        if status != "ok":
            message = fl.xml_text(message)
            ET.SubElement(tc, "skipped" if status == "skipped" else "failure", message=message[:2000]).text = message
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)


def ancestors(pid):
    """Command names of the process and its parents."""
    names = []
    while pid > 1:
        try:
            with open("/proc/%d/status" % pid) as f:
                status = dict(line.split(":", 1) for line in f if ":" in line)
        except OSError:
            break
        names.append(status["Name"].strip())
        pid = int(status["PPid"])
    return names


def one_run(log_path):
    """The launched gear_simulator: registered, one run published: its pid."""
    import rosgraph
    import rospy
    from gear_dynamics.msg import GearState
    from simtest import Collector, ends_at, services, wait_until
    state = Collector("/gear/state", GearState)
    master = rosgraph.Master("/remote_test")

    def registered():
        try:
            master.lookupNode("/gear/gear_simulator")
            return True
        except Exception:
            return False
    try:
        wait_until(registered, 60.0, "/gear/gear_simulator to register")
    except AssertionError as e:
        with open(log_path) as f:
            raise AssertionError("%s; roslaunch said:\n%s" % (e, f.read()[-3000:]))
    state.wait_connected(30.0)
    srv = services("/gear/gear_simulator")
    srv["reset"]()
    srv["unpause"]()
    msgs = state.wait_for(ends_at(T_END), 30.0, "t_end")
    uri = master.lookupNode("/gear/gear_simulator")
    _, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/remote_test")
    state.clear()
    rospy.loginfo("remote_test: %d states", len(msgs))
    return pid


def launch(args, env, log_path):
    log = open(log_path, "w")
    return subprocess.Popen(["roslaunch", "gear_dynamics", "remote_simulator.launch", "paused:=true",
                             "t_end:=%r" % T_END, "real_time_factor:=0", "output:=log"] + args,
                            env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def stop(p):
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGINT)
        try:
            p.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            raise AssertionError("roslaunch did not stop on SIGINT within 30 s")


def wait_unregistered():
    import rosgraph
    from simtest import wait_until
    master = rosgraph.Master("/remote_test")

    def gone():
        try:
            master.lookupNode("/gear/gear_simulator")
            return False
        except Exception:
            return True
    wait_until(gone, 20.0, "/gear/gear_simulator to unregister")


def local_case(work):
    log_path = os.path.join(work, "local_roslaunch.log")
    p = launch(["address:=localhost"], dict(os.environ), log_path)
    try:
        pid = one_run(log_path)
        chain = ancestors(pid)
        assert "sshd" not in chain, "the local machine went through sshd: %s" % chain
        assert "roslaunch" in chain or any("python" in c for c in chain[1:]), chain
        print("remote_test: local machine: gear_simulator pid %d, parents %s" % (pid, " < ".join(chain)), flush=True)
    finally:
        stop(p)
    wait_unregistered()


class Sshd:
    """An sshd of the test's own on 127.0.0.1:port, root login with the test's key only."""

    def __init__(self, work):
        self.dir = os.path.join(work, "sshd")
        os.makedirs(self.dir, mode=0o700)
        self.port = fl.free_port()
        self.home = os.path.join(work, "home")
        ssh = os.path.join(self.home, ".ssh")
        os.makedirs(ssh, mode=0o700)
        host_key = os.path.join(self.dir, "host_ed25519")
        subprocess.run(["ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", host_key], check=True)
        subprocess.run(["ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", os.path.join(ssh, "id_ed25519")],
                       check=True)
        shutil.copy(os.path.join(ssh, "id_ed25519.pub"), os.path.join(self.dir, "authorized_keys"))
        with open(host_key + ".pub") as f:
            pub = " ".join(f.read().split()[:2])
        with open(os.path.join(ssh, "known_hosts"), "w") as f:
            # roslaunch checks the bare name, paramiko then "[name]:port".
            f.write("localhost %s\n[localhost]:%d %s\n" % (pub, self.port, pub))
        conf = os.path.join(self.dir, "sshd_config")
        with open(conf, "w") as f:
            f.write("Port %d\nListenAddress 127.0.0.1\nHostKey %s\nPidFile %s\nAuthorizedKeysFile %s\n"
                    "PermitRootLogin prohibit-password\nPasswordAuthentication no\nKbdInteractiveAuthentication no\n"
                    "PubkeyAuthentication yes\nUsePAM no\nStrictModes no\nLogLevel VERBOSE\n" % (
                        self.port, host_key, os.path.join(self.dir, "sshd.pid"),
                        os.path.join(self.dir, "authorized_keys")))
        # The privilege-separation folder sshd insists on (Debian's service creates it at boot).
        self.made_run_dir = not os.path.isdir("/run/sshd")
        if self.made_run_dir:
            os.makedirs("/run/sshd", mode=0o755)
        self.log = open(os.path.join(self.dir, "sshd.log"), "w")
        self.process = subprocess.Popen([SSHD, "-D", "-e", "-f", conf], stdout=self.log, stderr=subprocess.STDOUT)
        from simtest import wait_until

        def listening():
            import socket
            with socket.socket() as s:
                return s.connect_ex(("127.0.0.1", self.port)) == 0
        wait_until(lambda: listening() or self.process.poll() is not None, 20.0, "sshd to listen")
        assert self.process.poll() is None, "sshd exited %s: %s" % (self.process.returncode, self.text())

    def text(self):
        with open(os.path.join(self.dir, "sshd.log")) as f:
            return f.read()[-3000:]

    def close(self):
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self.made_run_dir:
            shutil.rmtree("/run/sshd", ignore_errors=True)


def ssh_case(work):
    sshd = Sshd(work)
    try:
        env = dict(os.environ, HOME=sshd.home, USER="gd_remote_test", LOGNAME="gd_remote_test",
                   ROS_HOME=os.environ.get("ROS_HOME", work), ROS_IP="127.0.0.1")
        env.pop("ROS_HOSTNAME", None)
        env.pop("ROSLAUNCH_SSH_UNKNOWN", None)  # the host key must be checked, not accepted
        log_path = os.path.join(work, "ssh_roslaunch.log")
        p = launch(["address:=localhost", "user:=root", "ssh_port:=%d" % sshd.port], env, log_path)
        try:
            pid = one_run(log_path)
            chain = ancestors(pid)
            assert "sshd" in chain, "gear_simulator (pid %d) is not under sshd: %s" % (pid, chain)
            with open(log_path) as f:
                text = f.read()
            print("remote_test: ssh machine: gear_simulator pid %d, parents %s" % (pid, " < ".join(chain)), flush=True)
            print("remote_test: roslaunch: %s" % " | ".join(l for l in text.splitlines()
                                                          if "remote" in l.lower() or "machine" in l.lower())[:800],
                  flush=True)
            assert "Accepted publickey for root" in sshd.text(), "sshd did not log the key login:\n" + sshd.text()
        finally:
            stop(p)
        wait_unregistered()
    finally:
        sshd.close()


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    cases = []
    work = tempfile.mkdtemp(prefix="gd_remote_")
    os.chmod(work, 0o755)
    with fl.Master():
        import rospy
        rospy.init_node("remote_test", anonymous=True, disable_signals=True)
        for name, fn, skip in (
                ("local_machine", local_case, None),
                ("ssh_machine", ssh_case,
                 None if os.path.exists(SSHD) else "sshd is not installed (%s; scripts/test.sh installs "
                                                   "openssh-server)" % SSHD)):
            if skip:
                print("remote_test: SKIPPED %s: %s" % (name, skip), flush=True)
                cases.append((name, "skipped", skip, 0.0))
                continue
            start = time.time()
            try:
                fn(work)
                cases.append((name, "ok", "", time.time() - start))
            except Exception as e:
                traceback.print_exc()
                cases.append((name, "FAILED", "%s: %s" % (type(e).__name__, e), time.time() - start))
            print("[%s] remote/%s (%.1f s)" % (cases[-1][1], name, cases[-1][3]), flush=True)
    left = [pid for pid in os.listdir("/proc") if pid.isdigit() and int(pid) != os.getpid()
            and _mentions(pid, work)]
    if left:
        for pid in left:
            try:
                os.kill(int(pid), signal.SIGKILL)
            except OSError:
                pass
        cases.append(("cleanup", "FAILED", "processes left running (killed): %s" % left, 0.0))
    shutil.rmtree(work, ignore_errors=True)
    junit(args[0] if args else None, cases)
    return 1 if any(c[1] == "FAILED" for c in cases) else 0


def _mentions(pid, text):
    try:
        with open("/proc/%s/cmdline" % pid, "rb") as f:
            return text.encode() in f.read()
    except OSError:
        return False


if __name__ == "__main__":
    sys.exit(main())
