#!/usr/bin/env python3
# test/golden/golden.py: golden figures: runs a case's command lines, keeps the
# figures its [figures] section names from their --json summaries (and every
# step's exit code), compares them with the case's .out file (integers, flags
# and strings exactly, floats within a tolerance) or, with --regen, rewrites it.
"""Golden-figure regression runner (standard library only).

    golden.py [--regen] [--exact] [--threads N] [--keep] CASE.case...

A case file (INI syntax) has two sections:

    [steps]        one command line per step, run in order: NAME = PROG ARGS
                   PROG vm-* is $VM_BUILD_ROOT/apps/vm-*; in ARGS {tmp} is a
                   fresh temporary directory, {src} $VM_SOURCE_ROOT and {data}
                   $VM_SOURCE_ROOT/../shared/data (the case is skipped, exit
                   77, if a {data} file is missing)
    [figures]      STEP.FIELD[.SUBFIELD...] [= TOLERANCE], one per line:
                   FIELD of STEP's JSON summary (its stdout); TOLERANCE is
                   "exact", or "rel R" and/or "abs A" (pass if
                   |got - expected| <= max(A, R |expected|)). Default: exact
                   when both values are integers, flags, strings or null,
                   else rel 1e-6 abs 1e-12. Timings are refused.

Every step's exit code is a figure (STEP:exit, exact) without being listed.
The golden file is CASE.out beside the case: "STEP.FIELD JSON-VALUE" lines.
--regen (or VM_GOLDEN_REGEN=1 in the environment) rewrites it from this run
and prints what changed. --exact compares every figure bit for bit (is a
change "bit-identical"?); --threads N runs every step with N threads
(--threads arguments and OMP_NUM_THREADS) to check that the figures do not
depend on it; --keep leaves the temporary directory. Exit 0 all figures match, 1 a figure differs or a
step failed to give one, 2 usage or a malformed case, 77 skipped.
"""
import configparser
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

DEFAULT_REL = 1e-6
DEFAULT_ABS = 1e-12


class CaseError(Exception):
    pass


def is_timing(path):
    """Wall times differ from run to run: no case may keep one."""
    return any(p == "time" or p.startswith("time_") or p.endswith("_time") for p in path.split("."))


def parse_tolerance(text, where):
    """None (default rule), 'exact', or (rel, abs)."""
    text = (text or "").strip()
    if not text:
        return None
    if text == "exact":
        return "exact"
    words = text.split()
    rel = abs_ = 0.0
    if len(words) % 2:
        raise CaseError(f"{where}: tolerance '{text}': expected 'exact', 'rel R', 'abs A' or both")
    for key, val in zip(words[::2], words[1::2]):
        try:
            x = float(val)
        except ValueError:
            raise CaseError(f"{where}: tolerance '{text}': '{val}' is not a number")
        if key == "rel":
            rel = x
        elif key == "abs":
            abs_ = x
        else:
            raise CaseError(f"{where}: tolerance '{text}': unknown word '{key}'")
        if not (x >= 0 and math.isfinite(x)):
            raise CaseError(f"{where}: tolerance '{text}': must be finite and >= 0")
    return (rel, abs_)


def describe_tolerance(tol):
    if tol == "exact":
        return "exact"
    rel, abs_ = tol
    parts = ([f"rel {rel:g}"] if rel else []) + ([f"abs {abs_:g}"] if abs_ else [])
    return " ".join(parts) or "exact"


def read_case(path):
    cp = configparser.ConfigParser(allow_no_value=True, interpolation=None,
                                   delimiters=("=",), comment_prefixes=("#",),
                                   inline_comment_prefixes=None)
    cp.optionxform = str  # field names are case-sensitive (M_init)
    try:
        with open(path, encoding="utf-8") as f:
            cp.read_file(f)
    except (OSError, configparser.Error) as e:
        raise CaseError(f"{path}: {e}")
    for sec in ("steps", "figures"):
        if not cp.has_section(sec):
            raise CaseError(f"{path}: no [{sec}] section")
    extra = set(cp.sections()) - {"steps", "figures"}
    if extra:
        raise CaseError(f"{path}: unknown section(s) {sorted(extra)}")
    steps = []
    for name, cmd in cp.items("steps"):
        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", name):
            raise CaseError(f"{path}: step name '{name}': letters, digits, '_' and '-' only")
        if not cmd or not cmd.strip():
            raise CaseError(f"{path}: step '{name}' has no command")
        steps.append((name, " ".join(cmd.split())))
    names = {n for n, _ in steps}
    figures = []
    for key, tol in cp.items("figures"):
        step, _, field = key.partition(".")
        if step not in names or not field:
            raise CaseError(f"{path}: figure '{key}': expected STEP.FIELD with STEP one of {sorted(names)}")
        if is_timing(field):
            raise CaseError(f"{path}: figure '{key}' is a timing: timings are never compared")
        figures.append((key, parse_tolerance(tol, f"{path}: figure '{key}'")))
    return steps, figures


def read_golden(path):
    """{figure: value} from a .out file, or None if it does not exist."""
    if not os.path.exists(path):
        return None
    out = {}
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            key, _, val = line.partition(" ")
            try:
                out[key] = json.loads(val)
            except ValueError:
                raise CaseError(f"{path}:{n}: '{val}' is not a JSON value")
    return out


def fmt(v):
    return json.dumps(v)


def write_golden(path, case_path, figures):
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        f.write(f"# {os.path.basename(path)}: the golden figures of {os.path.basename(case_path)}; "
                "written by golden.py --regen\n")
        for key, val in figures.items():
            f.write(f"{key} {fmt(val)}\n")
    os.replace(path + ".tmp", path)


def lookup(obj, field):
    """obj's value at the dotted path field (list indices as numbers)."""
    cur = obj
    for part in field.split("."):
        if isinstance(cur, dict) and part in cur:
            cur = cur[part]
        elif isinstance(cur, list) and part.isdigit() and int(part) < len(cur):
            cur = cur[int(part)]
        else:
            raise KeyError(part)
    return cur


def is_int(v):
    return isinstance(v, int) and not isinstance(v, bool)


def compare(expected, got, tol):
    """(ok, the tolerance as used, a note on the difference)."""
    numeric = (is_int(expected) or isinstance(expected, float)) and \
              (is_int(got) or isinstance(got, float))
    if tol is None:
        tol = "exact" if not numeric or (is_int(expected) and is_int(got)) else (DEFAULT_REL, DEFAULT_ABS)
    if tol == "exact" or not numeric:
        return (type(expected) is type(got) and expected == got), "exact", ""
    rel, abs_ = tol
    diff = abs(got - expected)
    bound = max(abs_, rel * abs(expected))
    return diff <= bound, describe_tolerance(tol), f"|diff| {diff:.3g}, allowed {bound:.3g}"


def expand(arg, tmp, src, missing):
    data = os.path.normpath(os.path.join(src, "..", "shared", "data"))
    out = arg.replace("{tmp}", tmp).replace("{src}", src).replace("{data}", data)
    if "{data}" in arg and not os.path.exists(out):
        missing.append(out)
    return out


def run_case(case_path, regen, keep, exact=False, threads=None):
    src = os.environ.get("VM_SOURCE_ROOT") or os.path.normpath(
        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    build = os.environ.get("VM_BUILD_ROOT") or os.path.join(src, "build")
    case_path = os.path.abspath(case_path)
    name = os.path.splitext(os.path.basename(case_path))[0]
    shown = os.path.relpath(case_path, src) if case_path.startswith(os.path.abspath(src) + os.sep) else case_path
    golden_path = os.path.splitext(case_path)[0] + ".out"
    steps, wanted = read_case(case_path)
    golden = read_golden(golden_path)
    tmp = tempfile.mkdtemp(prefix=f"golden-{name}-")
    got = {}
    failures = []
    try:
        for step, cmd in steps:
            missing = []
            argv = [expand(a, tmp, src, missing) for a in shlex.split(cmd)]
            if missing:
                print(f"skip: {name}: {', '.join(missing)} not found")
                return 77
            if argv[0].startswith("vm-"):
                argv[0] = os.path.join(build, "apps", argv[0])
            env = None
            if threads:
                argv = [threads if i > 0 and argv[i - 1] == "--threads" else a
                        for i, a in enumerate(argv)]
                env = dict(os.environ, OMP_NUM_THREADS=threads)
            print(f"== {name}.{step}: {' '.join(shlex.quote(a) for a in argv)}", flush=True)
            t0 = time.monotonic()
            p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp,
                               env=env)
            dt = time.monotonic() - t0
            err = p.stderr.decode("utf-8", "replace")
            print(f"   exit {p.returncode} after {dt:.1f} s (not compared)")
            got[f"{step}:exit"] = p.returncode
            tail = "stderr ends:\n      " + "\n      ".join(err.strip().splitlines()[-8:])
            if golden and golden.get(f"{step}:exit", p.returncode) != p.returncode:
                why = f"killed by signal {-p.returncode}" if p.returncode < 0 else f"exit {p.returncode}"
                failures.append(f"{step}:exit: {why}; {tail}")
                tail = "stderr above"
            fields = [k for k, _ in wanted if k.split(".", 1)[0] == step]
            if not fields:
                continue
            try:
                summary = json.loads(p.stdout.decode("utf-8", "replace"))
            except ValueError:
                failures.append(f"{step}: stdout is not one JSON summary (exit {p.returncode}); {tail}")
                continue
            for key in fields:
                try:
                    got[key] = lookup(summary, key.split(".", 1)[1])
                except KeyError as e:
                    failures.append(f"{key}: not in {step}'s JSON summary (no '{e.args[0]}'); "
                                    f"it has: {', '.join(summary) if isinstance(summary, dict) else type(summary).__name__}")
    finally:
        if keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)

    order = [f"{s}:exit" for s, _ in steps] + [k for k, _ in wanted]
    tols = {k: "exact" for k, _ in wanted} if exact else dict(wanted)
    if regen:
        if failures:
            print(f"FAIL: {name}: not regenerated, a figure could not be read:")
            for f in failures:
                print(f"  {f}")
            return 1
        new = {k: got[k] for k in order}
        old = golden or {}
        changed = [k for k in order if k in old and not (type(old[k]) is type(new[k]) and old[k] == new[k])]
        for k in order:
            if k not in old:
                print(f"  new      {k} = {fmt(new[k])}")
            elif k in changed:
                print(f"  changed  {k}: {fmt(old[k])} -> {fmt(new[k])}")
        for k in old:
            if k not in new:
                print(f"  dropped  {k} (was {fmt(old[k])})")
        write_golden(golden_path, case_path, new)
        print(f"regenerated {golden_path}: {len(new)} figures, {len(changed)} changed")
        return 0

    if golden is None:
        print(f"FAIL: {name}: no golden file {golden_path}; write it with golden.py --regen "
              f"(or VM_GOLDEN_REGEN=1 meson test --suite golden)")
        return 1
    rows = []  # the matching figures first, the failures last
    bad = []
    for k in order:
        if k not in got:
            bad.append(f"FAIL {k}: expected {fmt(golden.get(k))}, got nothing (see 'why' below)")
            continue
        if k not in golden:
            bad.append(f"FAIL {k}: not in the golden file (the case lists it): run --regen")
            continue
        ok, tdesc, note = compare(golden[k], got[k], tols.get(k))
        if ok:
            rows.append(f"ok   {k} = {fmt(got[k])}" + (f" ({tdesc}: {note})" if note and golden[k] != got[k] else ""))
        else:
            bad.append(f"FAIL {k}: expected {fmt(golden[k])}, got {fmt(got[k])} (tolerance {tdesc}"
                       + (f"; {note}" if note else "") + ")")
    for k in golden:
        if k not in tols and k not in order:
            bad.append(f"FAIL {k}: in the golden file but no longer in the case: run --regen")
    for r in rows + bad:
        print(f"  {r}")
    for f in failures:
        print(f"  why: {f}")
    if bad:
        print(f"FAIL: {name}: {len(bad)} of {len(order)} figures differ from {os.path.basename(golden_path)}\n"
              f"  (if the change is intended: VM_BUILD_ROOT=build python3 test/golden/golden.py --regen {shown}\n"
              f"  from the source root, and say in the commit what changed and why)")
        return 1
    print(f"ok: {name}: {len(order)} figures as in {os.path.basename(golden_path)}")
    return 0


def main(argv):
    regen = os.environ.get("VM_GOLDEN_REGEN", "") not in ("", "0")
    keep = exact = False
    threads = None
    cases = []
    args = iter(argv)
    for a in args:
        if a == "--threads":
            threads = next(args, "")
            if not threads.isdigit() or int(threads) < 1:
                print("golden.py: --threads expects a positive integer", file=sys.stderr)
                return 2
        elif a == "--exact":
            exact = True
        elif a == "--regen":
            regen = True
        elif a == "--keep":
            keep = True
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        elif a.startswith("-"):
            print(f"golden.py: unknown option {a}", file=sys.stderr)
            return 2
        else:
            cases.append(a)
    if not cases:
        print("usage: golden.py [--regen] [--exact] [--threads N] [--keep] CASE.case...", file=sys.stderr)
        return 2
    codes = []
    for c in cases:
        try:
            codes.append(run_case(c, regen, keep, exact, threads))
        except CaseError as e:
            print(f"golden.py: {e}", file=sys.stderr)
            codes.append(2)
    ran = [rc for rc in codes if rc != 77]
    return max(ran) if ran else 77


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
