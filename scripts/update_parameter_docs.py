#!/usr/bin/python3
"""Rewrites the parameter tables of the docs (between <!-- parameters: NAME --> and
<!-- /parameters -->) from the declarations, as `gear_run --print-parameters NAME` prints them.
test_parameters fails until the docs carry the generated tables; run this after changing a key.

usage (with the workspace sourced): python3 scripts/update_parameter_docs.py"""
import glob
import os
import re
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BLOCK = re.compile(r"(<!-- parameters: (\w+) -->\n)(.*?)(<!-- /parameters -->)", re.S)

for path in [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "doc", "*.md"))):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    table = lambda m: m.group(1) + subprocess.run(["rosrun", "gear_dynamics", "gear_run", "--print-parameters", m.group(2)],
                                                  check=True, capture_output=True, text=True).stdout + m.group(4)
    new = BLOCK.sub(table, text)
    if new != text:
        with open(path, "w", encoding="utf-8") as f:
            f.write(new)
        print(f"updated {os.path.relpath(path, ROOT)}")
