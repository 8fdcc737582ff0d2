#!/usr/bin/python3
"""scripts/slurm on a real Slurm (Debian's slurm-wlm 22.05 and munge) started here on localhost:
munged, slurmctld and slurmd as root with a minimal slurm.conf in a temporary folder (2 CPUs, one
partition, private state/spool folders, PID and log files there, free ports). Then:

  array     scripts/slurm/submit.sh test/slurm/study.yaml --shards 4: a 4-task array and the
            aggregator job (afterok); the report's CSV files must be byte-identical to the same
            batch run in one process and aggregated with the same settings;
  cancel    the same into a fresh folder, one task cancelled with scancel once some of its bags
            are written: the shard is left incomplete, the aggregator job is dropped (its
            dependency can no longer be met); the same submit.sh again resumes it, and the
            report's CSV files and every bag's messages must equal the one-process batch's;
  cleanup   every job ended, the daemons stopped, no process of ours left (also after a failure).

Skipped, with the reason printed, only where Slurm cannot run: its programs are not installed
(scripts/test.sh installs them) or the test is not root (SlurmUser=root).

usage: slurm_test.py [JUNIT.xml] [--keep]   (--keep: leave the temporary folder for inspection)"""
import filecmp
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "test", "faults"))
import faultlib as fl  # noqa: E402

STUDY = os.path.join(HERE, "study.yaml")
ANALYSIS = os.path.join(HERE, "study_analysis.yaml")
SUBMIT = os.path.join(REPO, "scripts", "slurm", "submit.sh")
SHARDS = 4
CANCELLED_TASK = 3
PROGRAMS = ("munged", "mungekey", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel")


class Cases:
    def __init__(self, xunit):
        self.xunit, self.cases = xunit, []

    def run(self, name, fn):
        start = time.time()
        try:
            fn()
            status, message = "ok", ""
        except Exception as e:
            traceback.print_exc()
            status, message = "FAILED", str(e) if isinstance(e, AssertionError) else "%s: %s" % (type(e).__name__, e)
        self.add(name, status, message, time.time() - start)
        return status == "ok"

    def add(self, name, status, message, seconds=0.0):
        self.cases.append((name, status, message, seconds))
        print("[%s] slurm/%s (%.1f s)%s" % (status, name, seconds, ": " + message if message else ""), flush=True)

    def finish(self):
        if self.xunit:
            suite = ET.Element("testsuite", name="slurm", tests=str(len(self.cases)), errors="0",
                               failures=str(sum(c[1] == "FAILED" for c in self.cases)),
                               skipped=str(sum(c[1] == "skipped" for c in self.cases)))
            for name, status, message, seconds in self.cases:
                tc = ET.SubElement(suite, "testcase", classname="slurm.slurm", name=name, time="%.3f" % seconds)
                if status != "ok":
                    text = fl.xml_text(message)
                    ET.SubElement(tc, "skipped" if status == "skipped" else "failure", message=text[:2000]).text = text
            os.makedirs(os.path.dirname(os.path.abspath(self.xunit)), exist_ok=True)
            ET.ElementTree(suite).write(self.xunit, encoding="utf-8", xml_declaration=True)
        return 1 if any(c[1] == "FAILED" for c in self.cases) else 0


def our_processes(markers, before):
    """Processes (pid, command) that this test started, found after the daemons stopped: any whose
    command line or environment names the temporary folder, and any slurmstepd that was not there
    before the test."""
    found = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace").strip()
            with open("/proc/%s/environ" % pid, "rb") as f:
                env = f.read().decode(errors="replace")
        except OSError:
            continue
        if any(m in cmd or m in env for m in markers) or (cmd.startswith("slurmstepd") and int(pid) not in before):
            found.append((int(pid), cmd))
    return found


def task_pids(job, task_id):
    """The processes of array task job_task_id on this machine: those whose environment names it."""
    wanted = (b"SLURM_ARRAY_JOB_ID=%s\0" % job.encode(), b"SLURM_ARRAY_TASK_ID=%d\0" % task_id)
    pids = set()
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/environ" % pid, "rb") as f:
                env = b"\0" + f.read()
        except OSError:
            continue
        if all(b"\0" + w in env for w in wanted):
            pids.add(int(pid))
    return pids


def signal_all(pids, sig):
    for pid in pids:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass


def slurmstepd_pids():
    pids = set()
    for pid in os.listdir("/proc"):
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                if f.read().startswith(b"slurmstepd"):
                    pids.add(int(pid))
        except (OSError, ValueError):
            pass
    return pids


class Cluster:
    """munged, slurmctld and slurmd in the foreground, children of this script, on localhost."""

    def __init__(self, work):
        self.work = work
        self.daemons = []  # (name, Popen)
        self.env = dict(os.environ, SLURM_CONF=os.path.join(work, "slurm.conf"))
        for sub in ("munge", "state", "spool", "log"):
            os.makedirs(os.path.join(work, sub), mode=0o700, exist_ok=True)

    def start(self):
        w = self.work
        munge = os.path.join(w, "munge")
        self.socket = os.path.join(munge, "munge.socket")
        subprocess.run(["mungekey", "--create", "--keyfile", os.path.join(munge, "munge.key")], check=True)
        self._spawn("munged", ["munged", "--foreground", "--force", "--key-file", os.path.join(munge, "munge.key"),
                               "--socket", self.socket, "--pid-file", os.path.join(munge, "munged.pid"),
                               "--log-file", os.path.join(munge, "munged.log"),
                               "--seed-file", os.path.join(munge, "munged.seed")])
        fl.wait_until(lambda: os.path.exists(self.socket), 20, "munged's socket")
        ctld_port, slurmd_port = fl.free_port(), fl.free_port()
        while slurmd_port == ctld_port:
            slurmd_port = fl.free_port()
        conf = """# Written by test/slurm/slurm_test.py: one node (this machine), 2 CPUs, one partition.
ClusterName=gdtest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
AuthType=auth/munge
AuthInfo=socket={socket}
CredType=cred/munge
StateSaveLocation={w}/state
SlurmdSpoolDir={w}/spool
SlurmctldPidFile={w}/slurmctld.pid
SlurmdPidFile={w}/slurmd.pid
SlurmctldLogFile={w}/log/slurmctld.log
SlurmdLogFile={w}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
ReturnToService=2
KillWait=15
SlurmdParameters=config_overrides
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=gd Nodes=localhost Default=YES MaxTime=INFINITE State=UP
""".format(ctld_port=ctld_port, slurmd_port=slurmd_port, socket=self.socket, w=w)
        with open(self.env["SLURM_CONF"], "w") as f:
            f.write(conf)
        self._spawn("slurmctld", ["slurmctld", "-D", "-i"])
        self._spawn("slurmd", ["slurmd", "-D", "-N", "localhost"])
        fl.wait_until(lambda: self.out(["sinfo", "-h", "-o", "%T"], check=False).strip() == "idle", 60,
                      "the node to be idle (sinfo)")

    def _spawn(self, name, cmd):
        log = open(os.path.join(self.work, "log", name + ".out"), "w")
        self.daemons.append((name, subprocess.Popen(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT)))

    def out(self, cmd, check=True):
        p = subprocess.run(cmd, env=self.env, capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError("%s exited %d: %s" % (" ".join(cmd), p.returncode, p.stderr.strip()))
        return p.stdout

    def submit(self, output, logs):
        """submit.sh: (array job id, aggregate job id)."""
        text = self.out(["bash", SUBMIT, STUDY, "--shards", str(SHARDS), "--cpus", "1", "--output", output,
                         "--analysis", ANALYSIS, "--no-plot", "--logs", logs, "--time", "00:10:00"])
        ids = dict(line.split() for line in text.splitlines() if line.strip())
        return ids["array"], ids["aggregate"]

    def states(self, job):
        """{job or array task id: state} of a job still known to slurmctld (MinJobAge)."""
        return {key: fields.get("JobState", "?") for key, fields in self.jobs(job).items()}

    def jobs(self, job):
        """{job or array task id: scontrol's fields (JobState, Reason, ...)}."""
        text = self.out(["scontrol", "-o", "show", "job", job], check=False)
        found = {}
        for line in text.splitlines():
            fields = dict(re.findall(r"(\w+)=(\S*)", line))
            key = fields.get("JobId", "?")
            if "ArrayTaskId" in fields:
                key = "%s_%s" % (fields.get("ArrayJobId"), fields["ArrayTaskId"])
            found[key] = fields
        return found

    def wait_idle(self, timeout):
        """Waits until the node takes jobs again (no job left completing), naming its state if not."""
        state = {}

        def idle():
            state["now"] = self.out(["sinfo", "-h", "-o", "%T %E"], check=False).strip()
            return state["now"].split()[:1] == ["idle"]
        try:
            fl.wait_until(idle, timeout, "the node to be idle")
        except AssertionError as e:
            raise AssertionError("%s (sinfo: %s)" % (e, state.get("now")))

    def diagnosis(self, job, logs):
        """What a failed wait on a job reports: each task's state and reason, the node's state and
        the tasks' and daemons' logs."""
        tasks = ["%s %s (%s)" % (k, f.get("JobState"), f.get("Reason")) for k, f in sorted(self.jobs(job).items())]
        node = self.out(["sinfo", "-h", "-o", "%T %E"], check=False).strip()
        ctld = os.path.join(self.work, "log", "slurmctld.log")
        tail = ""
        if os.path.exists(ctld):
            with open(ctld, errors="replace") as f:
                tail = "".join(f.readlines()[-30:])
        return "tasks: %s; node: %s\n%s\n---- slurmctld.log (end)\n%s" % (
            ", ".join(tasks), node, logs_text(logs), tail)

    def wait_ended(self, job, timeout):
        fl.wait_until(lambda: not self.out(["squeue", "-h", "-j", job], check=False).strip(), timeout,
                      "job %s to end" % job)
        return self.states(job)

    def stop(self):
        """Cancels what is left, stops slurmd, slurmctld and munged (by their pid), and returns
        the problems found (empty: clean)."""
        problems = []
        if any(name == "slurmctld" and p.poll() is None for name, p in self.daemons):
            left = self.out(["squeue", "-h", "-o", "%i"], check=False).split()
            if left:
                self.out(["scancel", "--full"] + left, check=False)
                try:
                    fl.wait_until(lambda: not self.out(["squeue", "-h"], check=False).strip(), 40, "jobs to end")
                except Exception as e:
                    problems.append(str(e))
        for name, p in reversed(self.daemons):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    problems.append("%s did not stop on SIGTERM; killed" % name)
                    p.kill()
                    p.wait()
        return problems


def load_params(*files):
    return fl.load_yaml(*files)


def one_process(work):
    """The batch in one process (gear_monte_carlo, 2 threads) and its report with the same
    analysis settings as the Slurm aggregator job: (folder, report)."""
    folder, report = os.path.join(work, "one_process"), os.path.join(work, "one_process_report")
    params = load_params(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")]
                         + [STUDY])
    params["monte_carlo"].update({"output_dir": folder, "threads": 2})
    start = time.time()
    code, out = fl.run_node("gear_monte_carlo", fl.node_name("batch"), params, timeout=300)
    assert code == 0, "the one-process batch exited %s:\n%s" % (code, out[-3000:])
    print("one-process batch: %d bags in %.1f s" % (len(fl.bags(folder)), time.time() - start), flush=True)
    params = load_params(fl.config_file("aggregator.yaml"), ANALYSIS)
    params.update({"folders": folder, "report_folder": report, "exit_when_done": True, "plot_script": ""})
    code, out = fl.run_node("gear_aggregator", fl.node_name("aggregator"), params, timeout=120)
    assert code == 0, "aggregator on the one-process batch exited %s:\n%s" % (code, out[-3000:])
    return folder, report


def compare_reports(reference, report, what):
    files = sorted(f for f in os.listdir(reference) if f.endswith(".csv"))
    assert files, "no CSV file in %s" % reference
    match, mismatch, errors = filecmp.cmpfiles(reference, report, files, shallow=False)
    assert not mismatch and not errors, "%s: report CSV files differ from the one-process batch's: %s" % (
        what, mismatch + errors)
    return match


def logs_text(logs):
    text = []
    for name in sorted(os.listdir(logs)) if os.path.isdir(logs) else []:
        with open(os.path.join(logs, name), errors="replace") as f:
            text.append("---- %s\n%s" % (name, f.read()[-2500:]))
    return "\n".join(text)


def shard_files(folder, shard):
    """The bag files the shard's manifest lists (None before the manifest exists)."""
    import yaml
    path = os.path.join(folder, "manifest_shard%dof%d.yaml" % (shard, SHARDS))
    try:
        with open(path) as f:
            m = yaml.safe_load(f)
    except (OSError, yaml.YAMLError):
        return None
    return [r["file"] for r in m.get("runs", [])], bool(m.get("complete"))


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    keep = "--keep" in sys.argv
    cases = Cases(args[0] if args else None)
    missing = [p for p in PROGRAMS if not shutil.which(p, path=os.environ.get("PATH", "") + ":/usr/sbin:/sbin")]
    if missing:
        reason = ("Slurm is not installed here (missing %s; scripts/test.sh installs slurm-wlm and munge with "
                  "apt-get, which failed or is unavailable)" % ", ".join(missing))
        print("slurm_test: SKIPPED: " + reason, flush=True)
        cases.add("slurm", "skipped", reason)
        return cases.finish()
    if os.geteuid() != 0:
        reason = "the test runs slurmctld and slurmd with SlurmUser=root, which needs root (euid %d)" % os.geteuid()
        print("slurm_test: SKIPPED: " + reason, flush=True)
        cases.add("slurm", "skipped", reason)
        return cases.finish()
    os.environ["PATH"] = os.environ.get("PATH", "") + ":/usr/sbin:/sbin"

    work = tempfile.mkdtemp(prefix="gd_slurm_")
    os.chmod(work, 0o700)
    before = slurmstepd_pids()
    cluster = Cluster(work)
    timings = {}
    master = None
    try:
        master = fl.Master()  # for the one-process reference only; the Slurm jobs start their own
        ref = {}

        def reference():
            ref["folder"], ref["report"] = one_process(work)
        if not cases.run("one_process_reference", reference):
            return cases.finish()

        def start():
            t = time.time()
            cluster.start()
            timings["daemons"] = time.time() - t
            print("slurm_test: munged, slurmctld, slurmd up in %.1f s (%s)" % (timings["daemons"], work), flush=True)
        if not cases.run("daemons_start", start):
            print(logs_text(os.path.join(work, "log")))
            return cases.finish()

        def array():
            output, logs = os.path.join(work, "array"), os.path.join(work, "array_logs")
            t0 = time.time()
            job, agg = cluster.submit(output, logs)
            states = cluster.wait_ended(job, 240)
            t1 = time.time()
            agg_states = cluster.wait_ended(agg, 120)
            t2 = time.time()
            timings["array"], timings["aggregator"] = t1 - t0, t2 - t1
            print("slurm_test: array of %d tasks %.1f s (submit to last task), aggregator job %.1f s more" % (
                SHARDS, t1 - t0, t2 - t1), flush=True)
            assert sorted(states.values()) == ["COMPLETED"] * SHARDS and agg_states.get(agg) == "COMPLETED", \
                "job states %s, aggregator %s\n%s" % (states, agg_states, logs_text(logs))
            assert fl.bags(output) == fl.bags(ref["folder"]), "the array's bags are not the one-process batch's"
            files = compare_reports(ref["report"], os.path.join(output, "report"), "array")
            print("slurm_test: array: %d bags; CSV files byte-identical to one process: %s" % (
                len(fl.bags(output)), ", ".join(files)), flush=True)
        cases.run("array_matches_one_process", array)

        def cancel_resubmit():
            output, logs = os.path.join(work, "cancel"), os.path.join(work, "cancel_logs")
            cluster.wait_idle(60)
            job, agg = cluster.submit(output, logs)
            task = "%s_%d" % (job, CANCELLED_TASK)
            progress = {}

            def some_bags():
                found = shard_files(output, CANCELLED_TASK)
                if not found:
                    return False
                files, complete = found
                done = [f for f in files if os.path.exists(os.path.join(output, f))]
                progress.update(done=len(done), total=len(files), complete=complete)
                return bool(done)
            # The task starts once two of the others have ended (2 CPUs, 1 each): it is waited for
            # first, so that a slow machine is told apart from a task that never starts.
            try:
                def started():  # a pending task is listed under the array's range, not by its id
                    time.sleep(0.2)
                    return cluster.states(job).get(task, "PENDING") != "PENDING"
                fl.wait_until(started, 300, "task %s to start" % task)
                # On a fast machine the shard's bags follow each other faster than a poll and
                # scancel's round trip: the task runs in short slices between SIGSTOPs, and is
                # looked at and cancelled only while stopped.
                pids = set()

                def found_pids():
                    pids.update(task_pids(job, CANCELLED_TASK))
                    return bool(pids)
                fl.wait_until(found_pids, 60, "task %s's processes" % task)
                signal_all(pids, signal.SIGSTOP)
                deadline = time.time() + 120
                while not some_bags():
                    assert time.time() < deadline, "task %s wrote no bag in 120 s of slices" % task
                    pids.update(task_pids(job, CANCELLED_TASK))
                    signal_all(pids, signal.SIGCONT)
                    time.sleep(0.02)
                    signal_all(pids, signal.SIGSTOP)
            except AssertionError as e:
                raise AssertionError("%s\n%s" % (e, cluster.diagnosis(job, logs)))
            cluster.out(["scancel", task])
            # slurmstepd sends SIGCONT before SIGTERM; sent here too, once the cancel is recorded.
            fl.wait_until(lambda: cluster.states(job).get(task) != "RUNNING", 60, "task %s to leave RUNNING" % task)
            signal_all(pids, signal.SIGCONT)
            states = cluster.wait_ended(job, 120)
            agg_states = cluster.wait_ended(agg, 60)
            files, complete = shard_files(output, CANCELLED_TASK)
            done = [f for f in files if os.path.exists(os.path.join(output, f))]
            active = sorted(f for f in os.listdir(output) if f.endswith(".bag.active"))
            print("slurm_test: cancelled %s at %d/%d bags: after the cancel %d/%d bags, %d .bag.active (%s), "
                  "states %s, aggregator %s" % (task, progress["done"], progress["total"], len(done), len(files),
                                                len(active), ", ".join(active), states, agg_states), flush=True)
            assert states.get(task) == "CANCELLED", "task %s is %s, not CANCELLED" % (task, states.get(task))
            assert not complete and len(done) < len(files), \
                "the cancelled shard finished anyway (%d/%d bags): the cancel came too late" % (len(done), len(files))
            assert agg_states.get(agg) in ("CANCELLED", "PENDING", None) and \
                not os.path.exists(os.path.join(output, "report", "report.md")), \
                "the aggregator ran after a cancelled task: %s" % agg_states
            job2, agg2 = cluster.submit(output, logs)
            states2 = cluster.wait_ended(job2, 240)
            agg2_states = cluster.wait_ended(agg2, 120)
            assert sorted(states2.values()) == ["COMPLETED"] * SHARDS and agg2_states.get(agg2) == "COMPLETED", \
                "resubmission: job states %s, aggregator %s\n%s" % (states2, agg2_states, logs_text(logs))
            assert not [f for f in os.listdir(output) if f.endswith(".bag.active")], ".bag.active files left"
            assert fl.bags(output) == fl.bags(ref["folder"]), "after the resubmission the bags differ in name"
            differ = [b for b in fl.bags(output) if fl.read_bag(os.path.join(output, b)) !=
                      fl.read_bag(os.path.join(ref["folder"], b))]
            assert not differ, "after the resubmission these bags' messages differ: %s" % differ
            files = compare_reports(ref["report"], os.path.join(output, "report"), "cancel + resubmit")
            print("slurm_test: cancel + resubmit: every bag's messages and the CSV files (%s) identical to one "
                  "process" % ", ".join(files), flush=True)
        cases.run("cancel_resubmit_matches_one_process", cancel_resubmit)
    finally:
        def cleanup():
            problems = cluster.stop()
            if master:
                master.close()
            time.sleep(0.5)
            left = our_processes([work], before)
            for pid, _ in left:  # ours by construction (they name the test's folder); after the report
                try:
                    os.kill(pid, signal.SIGKILL)
                except OSError:
                    pass
            if left:
                problems.append("processes left running (now killed): %s" % left)
            assert not problems, "; ".join(problems)
            print("slurm_test: daemons stopped, no process of the test left", flush=True)
        cases.run("cleanup", cleanup)
        if timings:
            print("slurm_test: timings: " + ", ".join("%s %.1f s" % kv for kv in timings.items()), flush=True)
        if keep:
            print("slurm_test: kept %s" % work)
        else:
            shutil.rmtree(work, ignore_errors=True)
    return cases.finish()


if __name__ == "__main__":
    sys.exit(main())
