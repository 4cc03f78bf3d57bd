#!/usr/bin/env python3
"""Window choice of tools/make_eval_set.py on trajectories with known answers."""

import importlib.util
import pathlib
import sys
import unittest

spec = importlib.util.spec_from_file_location(
    "make_eval_set", pathlib.Path(__file__).resolve().parent.parent / "tools" / "make_eval_set.py")
make_eval_set = importlib.util.module_from_spec(spec)
spec.loader.exec_module(make_eval_set)


def line(t_begin, t_end, speed, x0=0.0, rate=100.0):
    """Poses along x at `speed` m/s, sampled at `rate` Hz over [t_begin, t_end]."""
    n = int(round((t_end - t_begin) * rate))
    return [(t_begin + k / rate, x0 + speed * k / rate, 0.0, 0.0) for k in range(n + 1)]


class PickWindow(unittest.TestCase):
    def test_fastest_gap_free_window(self):
        # 0-20 s slow, 20-40 s fast, then a gap, then 41-66 s faster still but only 25 s long.
        rows = line(0, 20, 0.2) + line(20.01, 40, 1.0, x0=4.0) + line(41, 66, 3.0, x0=30.0)
        start, length, speed = make_eval_set.pick_window(rows, 30.0)
        self.assertEqual(length, 30.0)
        # The best 30 s before the gap ends at 40 s: 10 s slow + 20 s fast.
        self.assertAlmostEqual(start, 10.0, delta=0.02)
        self.assertAlmostEqual(speed, (0.2 * 10 + 1.0 * 20) / 30, delta=0.01)
        # A 20 s window also fits after the gap, where it is faster: it wins.
        start, length, speed = make_eval_set.pick_window(rows, 20.0)
        self.assertGreaterEqual(start, 41.0 - 0.02)  # any window of the constant-speed stretch
        self.assertLessEqual(start, 46.0 + 0.02)
        self.assertAlmostEqual(speed, 3.0, delta=0.01)

    def test_longest_stretch_when_no_window_fits(self):
        rows = line(0, 10, 1.0) + line(12, 30, 0.5, x0=20.0) + line(31, 35, 2.0, x0=40.0)
        start, length, speed = make_eval_set.pick_window(rows, 40.0)
        self.assertAlmostEqual(start, 12.0, delta=0.02)
        self.assertAlmostEqual(length, 18.0, delta=0.02)
        self.assertAlmostEqual(speed, 0.5, delta=0.01)


if __name__ == "__main__":
    sys.exit(unittest.main())
