"""One runner for the plain Python checks that catkin counts (test/layers, test/downstream): each case
is a function returning its problems (an AssertionError or OSError counts as one), printed as
`CLASS.NAME: ok|FAILED` and written as a JUnit test case."""
import os
import time
import xml.etree.ElementTree as ET


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
            ET.SubElement(case, "failure", message=problems[0][:200]).text = "\n".join(problems)
            for p in problems:
                print("  " + p)
    suite.set("tests", str(len(cases)))
    suite.set("failures", str(failures))
    suite.set("errors", "0")
    if junit_path:
        os.makedirs(os.path.dirname(junit_path), exist_ok=True)
        ET.ElementTree(suite).write(junit_path, encoding="utf-8", xml_declaration=True)
    return failures
