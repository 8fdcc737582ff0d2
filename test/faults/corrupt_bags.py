#!/usr/bin/python3
"""Corrupted bags fed to gear_aggregator: truncated at random offsets, random bytes flipped, a bag
of a different message type, a zero-length file, a directory named like a bag. The aggregator must
never crash, must skip a bag it cannot trust with a reason, and every run it counts must carry the
values of the intact bag (a damaged summary is never counted).

A damaged bag may still be counted when what the aggregator reads of it is intact: its values in
runs.csv must then equal the intact batch's, and its run_info and summary (as Python's rosbag
reads them, when it can) the original bytes. Otherwise it must be skipped with a reason."""
import os
import shutil
import tempfile

import faultlib as fl

OVERLAY = {
    "run": {"duration": 0.05, "window": 0.01, "snapshot_times": [0.05]},
    "monte_carlo": {"mu": [0.0, 0.04], "realizations": 3, "phase_ensemble": False, "record_rate": 10000.0,
                    "record_realizations": 1, "sparse_record_rate": 1000.0, "block_lanes": 4, "threads": 1},
}
JOINT_TIMES = OVERLAY["run"]["snapshot_times"]


def make_batch(folder):
    p = fl.load_yaml(*[fl.config_file(f) for f in ("gear_pair.yaml", "load.yaml", "run.yaml", "monte_carlo.yaml")])
    for section, values in OVERLAY.items():
        p[section].update(values)
    p["monte_carlo"]["output_dir"] = folder
    code, out = fl.run_node("gear_monte_carlo", fl.node_name("batch"), p, timeout=120)
    assert code == 0, "reference batch failed:\n" + out[-3000:]


def key_messages(path):
    """The raw bytes of a bag's run_info and summary messages as Python's rosbag reads them (those
    topics only, as the aggregator does), or None if it cannot."""
    import rosbag
    try:
        with rosbag.Bag(path) as bag:
            return [(t, m[1]) for t, m, _ in bag.read_messages(topics=["/gear/run_info", "/gear/summary"], raw=True)]
    except Exception:
        return None


def write_other_type_bag(path):
    """A readable bag with the run's topics carrying other message types."""
    import rosbag
    import rospy
    from std_msgs.msg import Float64, String
    with rosbag.Bag(path, "w") as bag:
        bag.write("/gear/run_info", String(data="not a RunInfo"), rospy.Time(1))
        bag.write("/gear/state", Float64(data=0.5), rospy.Time(1.01))
        bag.write("/gear/summary", Float64(data=1.0), rospy.Time(2))


class Reference:
    def __init__(self, work):
        self.folder = os.path.join(work, "reference")
        make_batch(self.folder)
        self.bags = fl.bags(self.folder)
        self.key = {b: key_messages(os.path.join(self.folder, b)) for b in self.bags}
        code, out, self.runs, _ = fl.run_aggregator(self.folder, os.path.join(work, "reference_report"), JOINT_TIMES)
        assert code == 0 and len(self.runs) == len(self.bags), "aggregator on the intact batch:\n" + out[-3000:]


def damaged_case(suite, ref, work, category, name, damage):
    """Copies the batch, damages one bag with damage(path, rng) and judges the aggregator."""
    folder = os.path.join(work, name)
    with suite.case(category, name):
        shutil.copytree(ref.folder, folder)
        bag = suite.random.choice(ref.bags)
        path = os.path.join(folder, bag)
        detail = damage(path, suite.random)
        # None: Python's rosbag cannot read them either; then the counted values decide.
        key = key_messages(path) if os.path.isfile(path) else []
        code, out, runs, inputs = fl.run_aggregator(folder, folder + "_report", JOINT_TIMES)
        assert not fl.died_of_signal(code), "%s: the aggregator crashed (%s) on %s (%s):\n%s" % (
            name, code, bag, detail, out[-3000:])
        assert code == 0, "%s: the aggregator failed (exit %s) on %s (%s):\n%s" % (name, code, bag, detail, out[-3000:])
        run = bag[:-len(".bag")]
        reasons = [r["reason"] for r in inputs if os.path.basename(r["item"]) == bag and r["status"] == "skipped"]
        if run in runs:
            assert key in (None, ref.key[bag]), "%s: %s (%s) was counted although its run_info/summary differ" % (
                name, bag, detail)
            assert runs[run] == ref.runs[run], "%s: %s counted with other values: %s vs %s" % (
                name, bag, runs[run], ref.runs[run])
        else:
            assert reasons and reasons[0], "%s: %s (%s) neither counted nor skipped with a reason: %s" % (
                name, bag, detail, inputs)
        others = {r: v for r, v in runs.items() if r != run}
        assert others == {r: v for r, v in ref.runs.items() if r != run}, "%s: the other runs changed" % name
        print("  %s: %s %s -> %s" % (name, bag, detail, "counted (intact)" if run in runs else "skipped: " + reasons[0]))
    shutil.rmtree(folder, ignore_errors=True)
    shutil.rmtree(folder + "_report", ignore_errors=True)


def truncate(path, rng):
    size = os.path.getsize(path)
    offset = rng.randrange(1, size)
    with open(path, "r+b") as f:
        f.truncate(offset)
    return "truncated to %d of %d bytes" % (offset, size)


def flip(path, rng):
    size = os.path.getsize(path)
    offsets = sorted(rng.randrange(size) for _ in range(rng.choice((1, 1, 4))))
    with open(path, "r+b") as f:
        for o in offsets:
            f.seek(o)
            b = f.read(1)[0]
            f.seek(o)
            f.write(bytes([b ^ rng.randrange(1, 256)]))
    return "bytes flipped at %s of %d" % (offsets, size)


def other_type(path, rng):
    os.remove(path)
    write_other_type_bag(path)
    return "replaced by a bag of std_msgs types"


def zero_length(path, rng):
    open(path, "w").close()
    return "emptied"


def directory(path, rng):
    os.remove(path)
    os.mkdir(path)
    return "replaced by a directory"


def run(suite):
    work = tempfile.mkdtemp(prefix="gd_corrupt_bags_")
    try:
        ref = Reference(work)
        n = 12 if suite.args.slow else 3
        for i in range(n):
            damaged_case(suite, ref, work, "bag_truncated", "truncated_%d" % i, truncate)
        for i in range(n):
            damaged_case(suite, ref, work, "bag_bytes_flipped", "flipped_%d" % i, flip)
        damaged_case(suite, ref, work, "bag_other_type", "other_message_types", other_type)
        damaged_case(suite, ref, work, "bag_zero_length", "zero_length", zero_length)
        damaged_case(suite, ref, work, "bag_is_directory", "directory_named_like_a_bag", directory)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    fl.main(run)
