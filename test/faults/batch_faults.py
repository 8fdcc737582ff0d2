#!/usr/bin/python3
"""Faults in a Monte Carlo batch: SIGINT, SIGTERM and SIGKILL at random moments, the output folder
made unwritable mid-run, the disk filling up (a small tmpfs). After each: every .bag in the folder
is complete and readable, the aggregator counts exactly those bags (no partial one), and a resume
completes the batch to bags and report CSV files byte-identical to an uninterrupted batch. And the
README's main command (scripts/reproduce.sh) when its batch node does not finish cleanly: it fails.

Quick selection by default (one or two cases of each kind); --slow runs more random moments."""
import ctypes
import filecmp
import os
import shutil
import signal
import subprocess
import tempfile
import time

import faultlib as fl

# A small batch that still takes a couple of seconds, so that a random moment mostly falls inside
# it: 2 mu x (S1 + 8 realizations), every run recorded, blocks of 2 lanes on 1 thread.
OVERLAY = {
    "run": {"duration": 0.4, "window": 0.05, "snapshot_times": [0.2, 0.4]},
    "monte_carlo": {"mu": [0.0, 0.04], "realizations": 8, "phase_ensemble": False, "record_rate": 10000.0,
                    "record_realizations": 2, "sparse_record_rate": 1000.0, "block_lanes": 2, "threads": 1},
}
JOINT_TIMES = OVERLAY["run"]["snapshot_times"]
STOP_TIMEOUT = 30.0  # [s] a stopped batch must have ended by then


def batch_params(folder):
    p = fl.load_yaml(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")])
    for section, values in OVERLAY.items():
        p[section].update(values)
    p["monte_carlo"]["output_dir"] = folder
    return p


def drop_dac_override():
    """Root ignores permission bits: the child gives up CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH
    (from its bounding set, so exec does not restore them) and meets a read-only folder as a
    user would."""
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (1, 2):  # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        if libc.prctl(24, cap, 0, 0, 0) != 0:  # PR_CAPBSET_DROP
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP)")


class Batch:
    """One batch node run into `folder`, with its log kept for the messages."""

    def __init__(self, folder, preexec_fn=None):
        self.log = tempfile.TemporaryFile("w+")
        self.started = time.time()
        self.process = fl.start_node("gear_monte_carlo", fl.node_name("batch"), batch_params(folder),
                                     preexec_fn=preexec_fn, output=self.log)

    def wait(self, timeout):
        try:
            code = self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
            raise AssertionError("the batch did not end within %g s:\n%s" % (timeout, self.output()[-3000:]))
        return code

    def output(self):
        self.log.seek(0)
        return self.log.read()


def run_batch(folder, timeout=120):
    b = Batch(folder)
    code = b.wait(timeout)
    assert code == 0, "batch into %s exited %s:\n%s" % (folder, code, b.output()[-3000:])
    return time.time() - b.started


def fatal_line(output):
    lines = [l for l in output.splitlines() if "FATAL" in l]
    return lines[-1].split("]: ", 1)[-1].strip("\x1b[0m") if lines else "(no error logged)"


def csv_files(report):
    return sorted(f for f in os.listdir(report) if f.endswith(".csv"))


class Reference:
    """The uninterrupted batch: its bags' messages and the aggregator's CSV files."""

    def __init__(self, work):
        self.folder = os.path.join(work, "reference")
        self.wall = run_batch(self.folder)
        self.messages = {b: fl.check_run_bag(os.path.join(self.folder, b)) for b in fl.bags(self.folder)}
        self.size = sum(os.path.getsize(os.path.join(self.folder, f)) for f in os.listdir(self.folder))
        self.report = os.path.join(work, "reference_report")
        code, out, runs, _ = fl.run_aggregator(self.folder, self.report, JOINT_TIMES)
        assert code == 0 and len(runs) == len(self.messages), "aggregator on the reference batch:\n" + out[-3000:]
        print("reference batch: %d bags, %.0f kB, %.2f s wall" % (len(self.messages), self.size / 1e3, self.wall),
              flush=True)


def check_after_fault(folder, report, what):
    """Every .bag complete and readable; the aggregator counts exactly them and names every
    .bag.active as skipped (or, with nothing usable, refuses cleanly)."""
    complete = fl.bags(folder)
    for b in complete:
        fl.check_run_bag(os.path.join(folder, b))
    active = sorted(f for f in os.listdir(folder) if f.endswith(".bag.active"))
    code, out, runs, inputs = fl.run_aggregator(folder, report, JOINT_TIMES)
    assert not fl.died_of_signal(code), "%s: the aggregator crashed (%s):\n%s" % (what, code, out[-3000:])
    has_manifest = any(f.startswith("manifest") and f.endswith(".yaml") for f in os.listdir(folder))
    if not complete or not has_manifest:
        assert code != 0 and ("no usable bag" in out or "no manifest" in out), \
            "%s: with %d bags and %s manifest the aggregator should refuse, exit %s:\n%s" % (
                what, len(complete), "a" if has_manifest else "no", code, out[-3000:])
        return len(complete), len(active)
    assert code == 0, "%s: the aggregator failed (exit %s):\n%s" % (what, code, out[-3000:])
    counted = sorted(name + ".bag" for name in runs)
    assert counted == complete, "%s: the aggregator counted %s, the complete bags are %s" % (what, counted, complete)
    skipped = {os.path.basename(r["item"]) for r in inputs if r["status"] == "skipped" and r["reason"]}
    assert set(active) <= skipped, "%s: unfinished bags %s not reported skipped (inputs: %s)" % (
        what, sorted(set(active) - skipped), inputs)
    return len(complete), len(active)


def resume_and_compare(reference, folder, report, what):
    run_batch(folder)
    got = {b: fl.check_run_bag(os.path.join(folder, b)) for b in fl.bags(folder)}
    assert sorted(got) == sorted(reference.messages), "%s: after resume the bags are %s, expected %s" % (
        what, sorted(got), sorted(reference.messages))
    differ = [b for b in got if got[b] != reference.messages[b]]
    assert not differ, "%s: after resume these bags differ from the uninterrupted batch: %s" % (what, differ)
    assert not [f for f in os.listdir(folder) if f.endswith(".bag.active")], "%s: .active files left" % what
    code, out, runs, _ = fl.run_aggregator(folder, report, JOINT_TIMES)
    assert code == 0 and len(runs) == len(reference.messages), "%s: aggregator after resume:\n%s" % (what, out[-3000:])
    files = csv_files(reference.report)
    _, mismatch, errors = filecmp.cmpfiles(reference.report, report, files, shallow=False)
    assert not mismatch and not errors, "%s: report files differ after resume: %s" % (what, mismatch + errors)


def signal_case(suite, reference, work, sig, index, earliest=0.05, latest=None):
    name = "%s_%d" % (signal.Signals(sig).name, index)
    folder, report = os.path.join(work, name), os.path.join(work, name + "_report")
    delay = suite.random.uniform(earliest, reference.wall if latest is None else latest)
    with suite.case("batch_signal", "%s_at_%.2fs" % (name, delay)):
        b = Batch(folder)
        time.sleep(delay)
        os.killpg(b.process.pid, sig) if sig == signal.SIGKILL else b.process.send_signal(sig)
        code = b.wait(STOP_TIMEOUT)
        if sig != signal.SIGKILL and code not in (0, -sig):  # -sig: before the node's handler was set
            assert code == 128 + sig, "%s: exit code %s, expected %d:\n%s" % (name, code, 128 + sig, b.output()[-3000:])
        if os.path.isdir(folder):
            n, active = check_after_fault(folder, report, name)
            print("  %s after %.2f s: exit %s, %d bags complete, %d unfinished" % (name, delay, code, n, active))
        else:  # stopped before it made the folder
            assert code in (-sig, 128 + sig), "%s: exit %s without making its folder:\n%s" % (name, code, b.output()[-3000:])
            print("  %s after %.2f s: exit %s before the folder was made" % (name, delay, code))
        resume_and_compare(reference, folder, report, name)
    shutil.rmtree(folder, ignore_errors=True)


def descendants(pid):
    """The processes below `pid` (from /proc): {pid: command name}."""
    children, names = {}, {}
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open("/proc/%s/stat" % entry) as f:
                stat = f.read()
        except OSError:  # ended meanwhile
            continue
        name, rest = stat[stat.index("(") + 1:stat.rindex(")")], stat[stat.rindex(")") + 2:].split()
        names[int(entry)] = name
        children.setdefault(int(rest[1]), []).append(int(entry))
    out, todo = {}, [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out[c] = names[c]
            todo.append(c)
    return out


def main_command_case(suite, work, what):
    """roslaunch exits 0 when a node dies, and the aggregator then reports the bags it finds: the
    main command must fail when its batch node did not finish cleanly, here killed by SIGKILL once
    its first bags are written (no FATAL line to see) or refusing its folder, and leave no report.md."""
    folder, report = os.path.join(work, "main_" + what), os.path.join(work, "main_%s_report" % what)
    with suite.case("main_command", what):
        os.makedirs(folder)
        if what == "refused_folder":
            open(os.path.join(folder, "notes.txt"), "w").close()  # not a batch folder: refused
        env = dict(os.environ, GD_OUTPUT=folder, GD_REPORT=report)
        # The clone's own path, not the workspace's symlink to it: setup.sh names the workspace after it.
        script = os.path.join(os.path.realpath(fl.package_dir()), "scripts", "reproduce.sh")
        p = subprocess.Popen(["bash", script], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            if what == "batch_killed":
                deadline = time.time() + 120
                while not any(f.endswith(".bag") for f in os.listdir(folder)):
                    assert time.time() < deadline and p.poll() is None, "no bag was written"
                    time.sleep(0.05)
                batch = [pid for pid, name in descendants(p.pid).items() if name.startswith("gear_monte_car")]
                assert batch, "no gear_monte_carlo below reproduce.sh"
                os.kill(batch[0], signal.SIGKILL)
            out, _ = p.communicate(timeout=180)
        finally:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
                p.communicate()
        assert p.returncode == 1, "reproduce.sh exited %s, expected 1:\n%s" % (p.returncode, out[-3000:])
        assert "did not finish cleanly" in out, "no reason given:\n%s" % out[-3000:]
        assert not os.path.exists(os.path.join(report, "report.md")), "a report.md was left"
    shutil.rmtree(folder, ignore_errors=True)
    shutil.rmtree(report, ignore_errors=True)


def unwritable_case(suite, reference, work, index):
    name = "unwritable_%d" % index
    folder, report = os.path.join(work, name), os.path.join(work, name + "_report")
    delay = suite.random.uniform(0.3, reference.wall)
    with suite.case("batch_unwritable", "%s_at_%.2fs" % (name, delay)):
        b = Batch(folder, preexec_fn=drop_dac_override if os.geteuid() == 0 else None)
        time.sleep(delay)
        os.chmod(folder, 0o555)
        try:
            code = b.wait(STOP_TIMEOUT)
            out = b.output()
            if code == 0:  # it had finished before the folder turned read-only
                assert len(fl.bags(folder)) == len(reference.messages), "exit 0 with an incomplete batch:\n" + out[-3000:]
            else:
                assert folder in out, "%s: exit %s without naming the folder:\n%s" % (name, code, out[-3000:])
            n, active = check_after_fault(folder, report, name)
            print("  %s after %.2f s: exit %s, %d bags complete, %d unfinished; %s" % (
                name, delay, code, n, active, fatal_line(out)))
        finally:
            os.chmod(folder, 0o755)
        resume_and_compare(reference, folder, report, name)
    shutil.rmtree(folder, ignore_errors=True)


def disk_full_case(suite, reference, work, index):
    name = "disk_full_%d" % index
    mount = os.path.join(work, name + "_tmpfs")
    folder, report = os.path.join(mount, "batch"), os.path.join(work, name + "_report")
    # Room for a random part of the batch, in whole pages.
    size = max(16, int(suite.random.uniform(0.2, 0.8) * reference.size / 4096)) * 4096
    os.makedirs(mount)
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=%d" % size, "tmpfs", mount],
                                           capture_output=True).returncode != 0:
        suite.skip("batch_disk_full", name, "mounting a tmpfs needs root (euid %d); not tried" % os.geteuid())
        return
    try:
        with suite.case("batch_disk_full", "%s_%dkB_of_%dkB" % (name, size // 1024, reference.size // 1024)):
            b = Batch(folder)
            code = b.wait(120)
            out = b.output()
            assert code not in (0, None) and not fl.died_of_signal(code), \
                "%s: the batch should fail on a full disk, exit %s:\n%s" % (name, code, out[-3000:])
            n, active = check_after_fault(folder, report, name)
            print("  %s (%d kB): exit %s, %d bags complete, %d unfinished; %s" % (
                name, size // 1024, code, n, active, fatal_line(out)))
            subprocess.run(["mount", "-o", "remount,size=%d" % (4 * reference.size + (1 << 20)), mount], check=True)
            resume_and_compare(reference, folder, report, name)
    finally:
        subprocess.run(["umount", mount])
        os.rmdir(mount)


def run(suite):
    work = tempfile.mkdtemp(prefix="gd_batch_faults_")
    try:
        reference = Reference(work)
        repeats = 4 if suite.args.slow else 1
        for sig, n in ((signal.SIGINT, repeats), (signal.SIGTERM, repeats), (signal.SIGKILL, 2 * repeats)):
            for i in range(n):
                signal_case(suite, reference, work, sig, i)
        # While the node starts (reads its parameters from the master, prepares the folder): a
        # signal there interrupts a parameter read, which the node must not take for a missing section
        # (exit 2 instead of 143).
        for i in range(2 * repeats):
            signal_case(suite, reference, work, (signal.SIGTERM, signal.SIGINT)[i % 2], repeats + i, 0.005, 0.05)
        for i in range(2 if suite.args.slow else 1):
            unwritable_case(suite, reference, work, i)
        for i in range(2 if suite.args.slow else 1):
            disk_full_case(suite, reference, work, i)
        for what in ("batch_killed", "refused_folder"):
            main_command_case(suite, work, what)
    finally:
        for root, dirs, _ in os.walk(work):
            for d in dirs:
                os.chmod(os.path.join(root, d), 0o755)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    fl.main(run)
