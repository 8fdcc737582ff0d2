#!/usr/bin/python3
"""The fault suite's table: cases tried, passed and skipped per category, totalled from the JUnit
files of a test run (the generated configuration gtests, suite Generated/Faults*, and the fault
scripts, classname faults.<category>). Exits non-zero if a case failed or a category that CI must
exercise has no case at all.

usage: summary.py TEST_RESULTS_DIR"""
import os
import sys
import xml.etree.ElementTree as ET

# Every kind of fault the suite must try in each run (a skipped case, shown with its reason, counts
# as present: e.g. the tmpfs case without root).
REQUIRED = ["config_missing", "config_wrong_type", "config_nan", "config_inf", "config_negative_or_zero",
            "config_out_of_range", "config_unknown_key", "config_inconsistent", "node_missing", "node_wrong_type",
            "node_nan", "node_inf", "node_unknown_key", "batch_signal", "batch_unwritable", "batch_disk_full",
            "bag_truncated", "bag_bytes_flipped", "bag_other_type", "bag_zero_length", "bag_is_directory",
            "reconfigure_out_of_range", "sanitizer_address", "sanitizer_thread"]


def category(testcase):
    """The fault category of a JUnit testcase, or None if it is not part of the fault suite."""
    classname, name = testcase.get("classname", ""), testcase.get("name", "")
    if classname.startswith("faults."):
        return classname[len("faults."):]
    if classname.startswith("Generated/Faults") and "__" in name:
        return "config_" + name.split("/")[-1].split("__")[0]
    return None


def main(results):
    counts = {}
    for root, _, files in os.walk(results):
        for f in files:
            if not f.endswith(".xml"):
                continue
            try:
                tree = ET.parse(os.path.join(root, f))
            except ET.ParseError:
                continue
            for tc in tree.iter("testcase"):
                c = category(tc)
                if c is None:
                    continue
                entry = counts.setdefault(c, [0, 0, 0])
                if tc.find("skipped") is not None:
                    entry[2] += 1
                    continue
                entry[0] += 1
                entry[1] += tc.find("failure") is None and tc.find("error") is None
    print("\nFault suite: cases per category")
    print("  %-32s %6s %6s %8s" % ("category", "tried", "passed", "skipped"))
    for c in sorted(counts):
        print("  %-32s %6d %6d %8d" % ((c,) + tuple(counts[c])))
    total = [sum(v[i] for v in counts.values()) for i in range(3)]
    print("  %-32s %6d %6d %8d" % (("all",) + tuple(total)))
    absent = [c for c in REQUIRED if c not in counts]
    if absent:
        print("fault suite: no case of %s ran" % ", ".join(absent))
    return 0 if total[0] == total[1] and not absent else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
