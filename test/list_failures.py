#!/usr/bin/python3
"""Prints each failed or erroneous test case of the JUnit files under a folder, with the first
line of its message and the last lines of the rest (where a test's diagnostics end: the output of
the process it watched), so the end of a long log says what failed and why (scripts/test.sh runs
it last).

usage: list_failures.py TEST_RESULTS_DIR"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

TAIL_LINES = 12
root = sys.argv[1]
failed = 0
for path in sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True)):
    try:
        cases = ET.parse(path).getroot().iter("testcase")
    except ET.ParseError as e:
        print(f"failed: {os.path.relpath(path, root)}: unreadable JUnit file ({e})")
        failed += 1
        continue
    for case in cases:
        for bad in list(case.findall("failure")) + list(case.findall("error")):
            detail = (bad.get("message") or bad.text or "").strip().splitlines() or [""]
            print(f"failed: {os.path.relpath(path, root)}: {case.get('classname')}.{case.get('name')}: "
                  f"{detail[0][:300]}")
            tail = detail[1:][-TAIL_LINES:]
            if len(detail) - 1 > len(tail):
                print(f"    [... {len(detail) - 1 - len(tail)} lines ...]")
            for line in tail:
                print(f"    {line[:200]}")
            failed += 1
if failed:
    print(f"{failed} failed test case(s) listed above")
