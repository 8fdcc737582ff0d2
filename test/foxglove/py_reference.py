#!/usr/bin/python3
"""rosbag's Python API (an independent reader: genpy's generated classes) on a bag: every
GearState, RunInfo, RunSummary and PoincarePoint as JSON for read_bags.js, in the format of cpp_reference
(integers as strings, doubles as JSON numbers, non-finite ones as "nan", "inf", "-inf").
usage: py_reference.py OUT.json FILE.bag...   (OUT.json: {bag path: {"messages": [...]}})"""
import json
import math
import sys

import genpy
import rosbag

TYPES = ("gear_dynamics/GearState", "gear_dynamics/RunInfo", "gear_dynamics/RunSummary", "gear_dynamics/PoincarePoint")


def value(v):
    if isinstance(v, bool):
        return v
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return v if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, (list, tuple)):
        return [value(x) for x in v]
    if isinstance(v, genpy.TVal):  # time, duration
        return {"sec": str(v.secs), "nsec": str(v.nsecs)}
    if isinstance(v, genpy.Message):
        return {name: value(getattr(v, name)) for name in v.__slots__}
    return v  # str


def read(path):
    out = []
    with rosbag.Bag(path) as bag:
        for topic, msg, t in bag.read_messages():
            if msg._type in TYPES:
                out.append({"topic": topic, "type": msg._type, "time": value(t), "fields": value(msg)})
    return {"messages": out}


if __name__ == "__main__":
    with open(sys.argv[1], "w") as f:
        json.dump({path: read(path) for path in sys.argv[2:]}, f, allow_nan=False)
