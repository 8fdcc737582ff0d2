#!/usr/bin/python3
"""One build for every x86-64 (doc/architecture.md, "Instruction sets"): each instruction-set variant of
the engine's hot paths keeps a single global symbol (so no inline or template copy is shared between
levels), no other object of the build holds AVX or AVX-512 instructions, gear_run forced to each
variant this CPU runs writes the same CSV bytes, and the same binaries under qemu-x86_64 as a Haswell
(AVX2, no AVX-512) and as a Nehalem (no AVX) choose those levels and write those bytes too.

usage: isa_check.py BUILD_DIR DEVEL_LIB_DIR CONFIG_DIR JUNIT_XML"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from junit_cases import run_cases  # noqa: E402

BUILD, LIB, CONFIG, JUNIT = sys.argv[1:5]
LEVELS = ["baseline", "avx2", "avx512"]
GEAR_RUN = os.path.join(LIB, "gear_run")
# S1 and 8 realizations over 0.2 s: the start-up rattle (located crossings) and the normals.
ARGS = ["--realizations", "8", "--set", "run.duration=0.2", "--set", "run.window=0.05"]


def gear_run(out, env=None, prefix=()):
    e = dict(os.environ, GEAR_DYNAMICS_CONFIG_DIR=CONFIG)
    e.pop("GEAR_DYNAMICS_ISA", None)
    e.update(env or {})
    p = subprocess.run([*prefix, GEAR_RUN, *ARGS, "--output", out], env=e, capture_output=True, text=True,
                       timeout=600)
    return p


def read(path):
    with open(path, "rb") as f:
        return f.read()


def one_global_symbol():
    problems = []
    for level in LEVELS:
        obj = os.path.join(BUILD, f"gd_isa_{level}.o")
        out = subprocess.run(["nm", "--defined-only", "--extern-only", obj], capture_output=True, text=True)
        names = [line.split()[-1] for line in out.stdout.splitlines() if line.strip()]
        if out.returncode != 0 or names != [f"gd_isa_kernels_{level}"]:
            problems.append(f"{obj}: global symbols {names} (rc {out.returncode}), expected only gd_isa_kernels_{level}")
    return problems


def wide_registers_only_in_variants():
    """Every object compiled outside the avx2 and avx512 variants: no ymm or zmm register (static
    initializers, inline code, the baseline variant)."""
    cache = read(os.path.join(BUILD, "..", "CMakeCache.txt")).decode()
    if re.search(r"^GEAR_DYNAMICS_NATIVE:BOOL=ON", cache, re.M):
        print("  GEAR_DYNAMICS_NATIVE=ON: the whole build is for this CPU; the scan checks the variants only")
        objects = []
    else:
        objects = [o for o in glob.glob(os.path.join(BUILD, "CMakeFiles", "*.dir", "**", "*.o"), recursive=True)
                   if "/gd_isa_avx2.dir/" not in o and "/gd_isa_avx512.dir/" not in o]
    objects.append(os.path.join(BUILD, "gd_isa_baseline.o"))
    problems = []
    for obj in objects:
        dis = subprocess.run(["objdump", "-d", "--no-show-raw-insn", obj], capture_output=True, text=True).stdout
        hits = [line.strip() for line in dis.splitlines() if "%ymm" in line or "%zmm" in line]
        if hits:
            problems.append(f"{obj}: {len(hits)} AVX/AVX-512 instructions, e.g. {hits[0]}")
    # The variants do hold them (the scan would find them).
    for level, reg in (("avx2", "%ymm"), ("avx512", "%zmm")):
        dis = subprocess.run(["objdump", "-d", os.path.join(BUILD, f"gd_isa_{level}.o")], capture_output=True,
                             text=True).stdout
        if reg not in dis:
            problems.append(f"gd_isa_{level}.o has no {reg} instruction: not compiled for its level")
    print(f"  {len(objects)} objects scanned")
    return problems


def forced_variants_agree():
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        ref = None
        for level in LEVELS:
            out = os.path.join(tmp, f"{level}.csv")
            p = gear_run(out, {"GEAR_DYNAMICS_ISA": level})
            if p.returncode != 0:
                # A level this CPU lacks: refused with a message naming the variable and the level.
                if "does not run" in p.stderr and "GEAR_DYNAMICS_ISA" in p.stderr:
                    print(f"  {level}: refused on this CPU ({p.stderr.strip().splitlines()[-1]})")
                    continue
                problems.append(f"{level}: rc {p.returncode}: {p.stderr.strip()}")
                continue
            if f"instruction set: {level} (forced by GEAR_DYNAMICS_ISA)" not in p.stdout:
                problems.append(f"{level}: the summary line does not name it: {p.stdout.splitlines()[:1]}")
            data = read(out)
            print(f"  {level}: {len(data)} bytes")
            if ref is None:
                ref = data
            elif data != ref:
                problems.append(f"{level}: CSV differs from baseline's")
        p = gear_run(os.path.join(tmp, "bad.csv"), {"GEAR_DYNAMICS_ISA": "sse9"})
        if p.returncode == 0 or "GEAR_DYNAMICS_ISA = 'sse9'" not in p.stderr or "baseline, avx2, avx512" not in p.stderr:
            problems.append(f"GEAR_DYNAMICS_ISA=sse9 not refused clearly: rc {p.returncode}, {p.stderr.strip()}")
    return problems


def other_cpus():
    """The binaries as built here under CPUs without AVX-512 (Haswell) and without AVX (Nehalem)."""
    qemu = shutil.which("qemu-x86_64")
    if qemu is None:
        print("  skipped: qemu-x86_64 absent (Debian package qemu-user, which scripts/test.sh installs)")
        return []
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        ref_path = os.path.join(tmp, "native.csv")
        p = gear_run(ref_path)
        if p.returncode != 0:
            return [f"native run: {p.stderr.strip()}"]
        ref = read(ref_path)
        for cpu, level in (("Haswell", "avx2"), ("Nehalem", "baseline")):
            out = os.path.join(tmp, f"{cpu}.csv")
            p = gear_run(out, prefix=(qemu, "-cpu", cpu))
            if p.returncode != 0:
                problems.append(f"-cpu {cpu}: rc {p.returncode}: {p.stderr.strip()[-500:]}")
                continue
            if f"instruction set: {level} (best this CPU runs)" not in p.stdout:
                problems.append(f"-cpu {cpu}: expected {level}: {p.stdout.splitlines()[:1]}")
            if read(out) != ref:
                problems.append(f"-cpu {cpu}: CSV differs from the native run's")
            print(f"  -cpu {cpu}: {level}, same bytes" if read(out) == ref else f"  -cpu {cpu}: differs")
        p = gear_run(os.path.join(tmp, "forced.csv"), {"GEAR_DYNAMICS_ISA": "avx512"}, prefix=(qemu, "-cpu", "Haswell"))
        if p.returncode == 0 or "does not run avx512" not in p.stderr:
            problems.append(f"avx512 forced on a Haswell not refused: rc {p.returncode}, {p.stderr.strip()[-300:]}")
    return problems


if __name__ == "__main__":
    sys.exit(1 if run_cases("isa", [("one_global_symbol_per_variant", one_global_symbol),
                                     ("wide_registers_only_in_variants", wide_registers_only_in_variants),
                                     ("forced_variants_agree", forced_variants_agree),
                                     ("other_cpus_same_bytes", other_cpus)], JUNIT) else 0)
