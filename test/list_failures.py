#!/usr/bin/python3
"""Prints one line per failed or erroneous test case of the JUnit files under a folder, with the
first lines of its message, so the end of a long log says what failed (scripts/test.sh runs it
last).

usage: list_failures.py TEST_RESULTS_DIR"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

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
            detail = (bad.get("message") or bad.text or "").strip().splitlines()
            print(f"failed: {os.path.relpath(path, root)}: {case.get('classname')}.{case.get('name')}: "
                  f"{' | '.join(detail[:3])[:300]}")
            failed += 1
if failed:
    print(f"{failed} failed test case(s) listed above")
