"""One runner for the plain Python checks that catkin counts (test/layers, test/downstream): each case
is a function returning its problems (an AssertionError or OSError counts as one), printed as
`CLASS.NAME: ok|FAILED` and written as a JUnit test case."""
import os
import re
import time
import xml.etree.ElementTree as ET

# Terminal escapes (roslaunch sets the window title, ROS logs are coloured) and the other characters
# XML 1.0 cannot hold: left in a failure's text they make the whole JUnit file unreadable.
_ESCAPE = re.compile(r"\x1b(\[[0-9;?]*[ -/]*[@-~]|\][^\x07\x1b]*(\x07|\x1b\\)?|.)", re.S)
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_text(text):
    """`text` without terminal escapes, other characters outside XML 1.0 as '?'."""
    return _NOT_XML.sub("?", _ESCAPE.sub("", text))


def run_cases(classname, cases, junit_path=None):
    """Runs the (name, check) pairs; returns the number of failed cases."""
    suite = ET.Element("testsuite", name=classname)
    failures = 0
    for name, check in cases:
        start = time.time()
        try:
            problems = check()
        except (AssertionError, OSError) as e:
            problems = [str(e)]
        case = ET.SubElement(suite, "testcase", classname=classname, name=name, time=f"{time.time() - start:.3f}")
        print(f"{classname}.{name}: {'ok' if not problems else 'FAILED'}")
        if problems:
            failures += 1
            text = xml_text("\n".join(problems))
            ET.SubElement(case, "failure", message=text.splitlines()[0][:200] if text else "").text = text
            for p in problems:
                print("  " + p)
    suite.set("tests", str(len(cases)))
    suite.set("failures", str(failures))
    suite.set("errors", "0")
    if junit_path:
        os.makedirs(os.path.dirname(junit_path), exist_ok=True)
        ET.ElementTree(suite).write(junit_path, encoding="utf-8", xml_declaration=True)
    return failures
