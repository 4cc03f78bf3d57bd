#!/usr/bin/env python3
"""Window choice and suite file of tools/make_eval_set.py on known inputs."""

import importlib.util
import json
import pathlib
import sys
import tempfile
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


class WriteSuite(unittest.TestCase):
    def test_lists_complete_renders_with_their_encodings(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = pathlib.Path(tmp)

            def touch(path):
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text("x")

            names = ["euroc_MH_03_medium-blur", "euroc_MH_03_medium-clean", "tumvi_room1_512_16-clean"]
            self.assertEqual(make_eval_set.write_suite(out, names, ["500k"], None), 0)
            self.assertFalse((out / "suite.json").exists())  # nothing rendered: no suite

            touch(out / "euroc_MH_03_medium-blur" / "calib.json")
            touch(out / "euroc_MH_03_medium-blur-500k" / "mav0" / "cam1" / "data.mp4")
            touch(out / "euroc_MH_03_medium-clean" / "mav0" / "cam0" / "data.csv")  # render not finished
            touch(out / "tumvi_room1_512_16-clean" / "calib.json")  # rendered, not encoded yet
            kitti = out / "kitti" / "sequences" / "06"
            kitti.mkdir(parents=True)
            touch(out / "kitti06-500k" / "mav0" / "cam1" / "data.mp4")
            self.assertEqual(make_eval_set.write_suite(out, names, ["250k", "500k"], kitti), 3)
            suite = json.loads((out / "suite.json").read_text())
            self.assertEqual(suite["bitrates"], ["raw", "250k", "500k"])
            self.assertIn("mv_parallel_of", suite["modes"])
            self.assertIn("mv", suite["modes"])  # the shipped configs' mode
            by_name = {s["name"]: s for s in suite["sequences"]}
            self.assertEqual(sorted(by_name), ["euroc_MH_03_medium-blur", "kitti06", "tumvi_room1_512_16-clean"])
            blur = by_name["euroc_MH_03_medium-blur"]
            self.assertEqual(blur["path"], "euroc_MH_03_medium-blur")  # relative to the suite file
            self.assertEqual(blur["encoded"], {"500k": "euroc_MH_03_medium-blur-500k"})
            self.assertEqual(blur["config"], "euroc")
            self.assertEqual(by_name["tumvi_room1_512_16-clean"]["config"], "tumvi")
            self.assertNotIn("encoded", by_name["tumvi_room1_512_16-clean"])
            self.assertEqual(by_name["kitti06"]["path"], str(kitti.resolve()))
            self.assertEqual(by_name["kitti06"]["config"], "kitti")
            self.assertEqual(by_name["kitti06"]["rules"], {"rte_divergence_m": 1.0})  # a street's 6 frames span metres
            self.assertNotIn("rules", blur)
            self.assertEqual(suite["repeats"], 3)


if __name__ == "__main__":
    sys.exit(unittest.main())
