#!/usr/bin/env python3
# test/golden/test_golden.py: the golden-figure runner checks itself: its
# comparisons and tolerances, the cases it refuses, and end to end on a tiny
# case that a changed figure fails with the figure's name, expected value,
# value got and tolerance, and that --regen makes it pass again.
import contextlib
import io
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import golden  # noqa: E402

TINY = """# a tiny case for the runner's own test
[steps]
gen = vm-gen rotcube --n 2 --angle pi/2 {tmp}/c.vtk
quality = vm-quality --json {tmp}/c.vtk

[figures]
quality.vertices
quality.all.elements
quality.all.phi_min = rel 1e-9
quality.sj_histogram
"""


def run(*args):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        rc = golden.main(list(args))
    return rc, out.getvalue()


class Compare(unittest.TestCase):
    def test_integers_exact(self):
        self.assertTrue(golden.compare(11, 11, None)[0])
        self.assertFalse(golden.compare(11, 12, None)[0])
        self.assertEqual(golden.compare(11, 12, None)[1], "exact")

    def test_flags_and_strings_exact(self):
        self.assertTrue(golden.compare(True, True, None)[0])
        self.assertFalse(golden.compare(True, False, None)[0])
        self.assertFalse(golden.compare(1, True, None)[0])
        self.assertFalse(golden.compare("corner", "geometric", (1.0, 1.0))[0])
        self.assertTrue(golden.compare(None, None, None)[0])
        self.assertFalse(golden.compare(None, 0.5, None)[0])

    def test_floats_default_tolerance(self):
        self.assertTrue(golden.compare(0.5, 0.5 * (1 + 1e-7), None)[0])
        self.assertFalse(golden.compare(0.5, 0.5 * (1 + 1e-5), None)[0])
        # a float printed as an integer ("%.17g" of 0.0) against a float
        self.assertFalse(golden.compare(0, 1e-3, None)[0])
        self.assertTrue(golden.compare(0, 1e-13, None)[0])

    def test_given_tolerances(self):
        self.assertTrue(golden.compare(1.0, 1.001, (1e-2, 0))[0])
        self.assertFalse(golden.compare(1.0, 1.001, "exact")[0])
        self.assertTrue(golden.compare(0.0, 1e-10, (0, 1e-9))[0])
        self.assertTrue(golden.compare(100, 102, (0, 2))[0])

    def test_parse_tolerance(self):
        self.assertIsNone(golden.parse_tolerance("", "x"))
        self.assertEqual(golden.parse_tolerance("exact", "x"), "exact")
        self.assertEqual(golden.parse_tolerance("rel 1e-4 abs 1e-9", "x"), (1e-4, 1e-9))
        for bad in ("rel", "rel x", "near 1", "rel -1", "abs nan"):
            with self.assertRaises(golden.CaseError):
                golden.parse_tolerance(bad, "x")

    def test_timings_refused(self):
        for f in ("time", "time_total", "adapt.time", "time.march", "solve_time"):
            self.assertTrue(golden.is_timing(f), f)
        for f in ("timed_out", "iter_untangle", "M_init"):
            self.assertFalse(golden.is_timing(f), f)


class EndToEnd(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.case = os.path.join(self.dir.name, "tiny.case")
        self.out = os.path.join(self.dir.name, "tiny.out")
        with open(self.case, "w") as f:
            f.write(TINY)

    def tearDown(self):
        self.dir.cleanup()

    def test_regen_compare_fail(self):
        rc, log = run(self.case)
        self.assertEqual(rc, 1, log)
        self.assertIn("no golden file", log)
        rc, log = run("--regen", self.case)
        self.assertEqual(rc, 0, log)
        self.assertIn("new      quality.all.elements = 8", log)
        rc, log = run(self.case)
        self.assertEqual(rc, 0, log)
        self.assertIn("ok: tiny: 6 figures as in tiny.out", log)
        rc, log = run("--exact", "--threads", "1", self.case)
        self.assertEqual(rc, 0, log)
        # change two figures: each failure names the figure, expected, got, tolerance
        with open(self.out) as f:
            text = f.read()
        with open(self.out, "w") as f:
            f.write(text.replace("quality.all.elements 8", "quality.all.elements 9")
                    .replace("quality.vertices 27", "quality.vertices 28"))
        rc, log = run(self.case)
        self.assertEqual(rc, 1, log)
        self.assertIn("FAIL quality.all.elements: expected 9, got 8 (tolerance exact)", log)
        self.assertIn("FAIL quality.vertices: expected 28, got 27 (tolerance exact)", log)
        self.assertIn("FAIL: tiny: 2 of 6 figures differ", log)
        rc, log = run("--regen", self.case)
        self.assertEqual(rc, 0, log)
        self.assertIn("changed  quality.all.elements: 9 -> 8", log)
        self.assertEqual(run(self.case)[0], 0)

    def test_step_failure_shows_stderr(self):
        run("--regen", self.case)
        with open(self.case, "w") as f:
            f.write(TINY.replace("--json {tmp}", "--json --rule nonsense {tmp}"))
        rc, log = run(self.case)
        self.assertEqual(rc, 1, log)
        self.assertIn("FAIL quality:exit: expected 0, got 2 (tolerance exact)", log)
        self.assertIn("FAIL quality.all.elements: expected 8, got nothing", log)
        self.assertIn("stderr ends:", log)

    def test_malformed_cases(self):
        for text, msg in (
                (TINY + "quality.time_total\n", "is a timing"),
                (TINY + "nosuchstep.x\n", "expected STEP.FIELD"),
                (TINY + "quality.M = rel\n", "tolerance"),
                (TINY.replace("[figures]", "[figurs]"), "no [figures] section")):
            with open(self.case, "w") as f:
                f.write(text)
            rc, log = run(self.case)
            self.assertEqual(rc, 2, log)
            self.assertIn(msg, log)


if __name__ == "__main__":
    unittest.main(verbosity=2)
