#!/usr/bin/python3
"""gear_dynamics as another catkin package uses it: a small package in a workspace of its own,
`find_package(catkin REQUIRED COMPONENTS gear_dynamics)`, includes every public header
(include/gear_dynamics/**/*.hpp) and calls a function of each exported library, linked through
`${catkin_LIBRARIES}` only. Checks that every library the package builds is exported
(catkin_package's LIBRARIES), that the downstream package configures, compiles and links, that
its executable records each exported library as needed, and that it runs.

Run with the package's workspace sourced (catkin_make run_tests does; so does scripts/setup.sh).
usage: downstream_test.py JUNIT_XML"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import run_cases  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# A function of each library, called by the downstream executable: with --as-needed (Debian's
# default) a library none of whose symbols is used is dropped, so each must be used to be checked.
CALLS = {
    "maths": "gd::wilson(3, 10).estimate + gd::welch_psd(std::vector<double>(64, 1.0), 1000.0, {16, 0.5}).sample_rate",
    "model": "gd::derive(gd::GearInputs{}).contact_ratio",
    "engine": "gd::grid_time(83123000, 1e-6)",
    "config": "gd::mu_label(0.04).size()",
    "batch": "gd::manifest_file_name(0, 1).size() + std::string(gd::to_string(gd::RunKind::S1)).size()",
    "live": "gd::to_string(gd::LoadInput::Sde).size()",
    "montecarlo": "gd::shard_runs({}, 0, 1).size()",
    "dynamics": "gd::LorenzLanes({}, 1e-3, {{1.0, 1.0, 1.0}}).time()",
    "analysis": "gd::analyse_study(gd::BatchInputs{}, gd::AnalysisSettings{}).points.size()",
    "report": "gd::paper_reference().size()",
    "monitor": "gd::indicator_names().size()",
    "ros": "gd::make_poincare_point(gd::SectionPoint{}).t",
    "aggregation": "static_cast<double>(gd::batch_complete(\"/nonexistent\"))",
}

PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>gd_downstream</name>
  <version>0.0.1</version>
  <description>Uses gear_dynamics as a downstream package does.</description>
  <maintainer email="nobody@example.com">nobody</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>gear_dynamics</depend>
</package>
"""

CMAKE = """cmake_minimum_required(VERSION 3.16)
project(gd_downstream LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
find_package(catkin REQUIRED COMPONENTS gear_dynamics)
catkin_package()
include_directories(${catkin_INCLUDE_DIRS})
add_executable(uses_gear_dynamics main.cpp)
target_link_libraries(uses_gear_dynamics ${catkin_LIBRARIES})
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/exported_libraries.txt "${gear_dynamics_LIBRARIES}")
"""


def public_headers():
    base = os.path.join(ROOT, "include")
    return sorted(os.path.relpath(p, base) for p in glob.glob(os.path.join(base, "gear_dynamics", "**", "*.hpp"),
                                                              recursive=True))


def built_libraries():
    """The package's own libraries, from its CMakeLists.txt: add_library(${PROJECT_NAME}_x ...)."""
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        return sorted(set(re.findall(r"^\s*add_library\(\$\{PROJECT_NAME\}_(\w+)", f.read(), re.M)))


def main_cpp():
    lines = [f'#include "{h}"' for h in public_headers()]
    lines += ["#include <cstdio>", "#include <string>", "#include <vector>", "",
              "namespace gd = gear_dynamics;", "", "int main() {", "  double sum = 0;"]
    lines += [f"  sum += {call};  // {lib}" for lib, call in CALLS.items()]
    lines += ['  std::printf("gd_downstream %g\\n", sum);', "  return 0;", "}", ""]
    return "\n".join(lines)


def run(cmd, cwd, log):
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    log.append(f"$ {' '.join(cmd)}\n{p.stdout}")
    return p


class Downstream:
    def __init__(self):
        self.ws = tempfile.mkdtemp(prefix="gd_downstream_")
        self.log = []
        self.built = None

    def build(self):
        """Writes the package and runs catkin_make; the executable's path, or None with the log."""
        if self.built is None:
            pkg = os.path.join(self.ws, "src", "gd_downstream")
            os.makedirs(pkg)
            for name, text in (("package.xml", PACKAGE_XML), ("CMakeLists.txt", CMAKE), ("main.cpp", main_cpp())):
                with open(os.path.join(pkg, name), "w", encoding="utf-8") as f:
                    f.write(text)
            p = run(["catkin_make", "-C", self.ws, "-DCMAKE_BUILD_TYPE=Release", "-DPYTHON_EXECUTABLE=/usr/bin/python3", "-j2"],
                    self.ws, self.log)
            exe = os.path.join(self.ws, "devel", "lib", "gd_downstream", "uses_gear_dynamics")
            self.built = exe if p.returncode == 0 and os.path.exists(exe) else ""
        return self.built

    def exported(self):
        path = os.path.join(self.ws, "build", "gd_downstream", "exported_libraries.txt")
        with open(path, encoding="utf-8") as f:
            return f.read().split(";")


def case_every_library_exported(d):
    if not d.build():
        return ["the downstream package did not build:\n" + d.log[-1][-4000:]]
    names = {os.path.basename(p) for p in d.exported()}
    return [f"gear_dynamics_{lib} is built but not in catkin_package(LIBRARIES ...) (exported: {sorted(names)})"
            for lib in built_libraries()
            if not any(re.fullmatch(rf"(lib)?gear_dynamics_{lib}(\.so.*)?", n) for n in names)]


def case_every_library_called(d):
    """CALLS must name each built library, so that a new library is checked too."""
    return [f"no call for the library gear_dynamics_{lib} in CALLS" for lib in built_libraries() if lib not in CALLS]


def case_links_and_runs(d):
    exe = d.build()
    if not exe:
        return ["the downstream package did not build:\n" + d.log[-1][-4000:]]
    needed = run(["readelf", "-d", exe], d.ws, d.log).stdout
    problems = [f"uses_gear_dynamics does not need libgear_dynamics_{lib}.so" for lib in CALLS
                if f"[libgear_dynamics_{lib}.so]" not in needed]
    p = run([exe], d.ws, d.log)
    if p.returncode != 0 or "gd_downstream" not in p.stdout:
        problems.append(f"uses_gear_dynamics exited {p.returncode}: {p.stdout[-2000:]}")
    return problems


def self_check(d):
    """The checks must catch what they are for: a header missing from main.cpp, a library left out."""
    text = main_cpp()
    assert all(f'#include "{h}"' in text for h in public_headers()), "a public header is not included"
    assert len(public_headers()) > 20, "no public headers found"
    assert "dynamics" in built_libraries() and "aggregation" in built_libraries(), built_libraries()
    return []


def main():
    d = Downstream()
    cases = [("checker_sees_headers_and_libraries", self_check), ("every_library_called", case_every_library_called),
             ("every_library_exported", case_every_library_exported), ("links_and_runs", case_links_and_runs)]
    failures = run_cases("downstream", [(name, lambda check=check: check(d)) for name, check in cases],
                         sys.argv[1] if len(sys.argv) > 1 else None)
    if failures:
        print(f"(workspace kept: {d.ws})")
    else:
        shutil.rmtree(d.ws, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
