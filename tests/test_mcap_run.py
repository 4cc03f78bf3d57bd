#!/usr/bin/env python3
"""`voca run --mcap` end to end, read back by the independent reader (tests/mcap_reader.py): every
estimated pose is in the recording, equal to its trajectory row; a run stopped by SIGINT leaves a
closed, readable file; a recording that cannot be written (/dev/full) is a warning, and the run and
its trajectory are what they are without --mcap.

    python3 tests/test_mcap_run.py --voca build/release/bin/voca --data ../shared/data
"""

import argparse
import json
import pathlib
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import mcap_reader  # noqa: E402

VOCA = None
EUROC = None
FRAMES = "40"


def tum_rows(path):
    """{t_ns: [x, y, z, qx, qy, qz, qw]} of a TUM file (its seconds have exactly nine decimals)."""
    rows = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if not line or line.startswith("#"):
            continue
        fields = line.split()
        seconds, nanos = fields[0].split(".")
        rows[int(seconds) * 1_000_000_000 + int(nanos)] = [float(x) for x in fields[1:]]
    return rows


def poses_of(recording):
    """{log_time: [x, y, z, qx, qy, qz, qw]} of the recording's /voca/pose messages."""
    topics = {c.id: c.topic for c in recording.channels.values()}
    poses = {}
    for message in recording.messages:
        if topics[message.channel_id] != "/voca/pose":
            continue
        pose = json.loads(message.data)["pose"]
        p, q = pose["position"], pose["orientation"]
        poses[message.log_time] = [p["x"], p["y"], p["z"], q["x"], q["y"], q["z"], q["w"]]
    return poses


class McapRunTest(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.TemporaryDirectory(prefix="voca-mcap-run-")
        self.dir = pathlib.Path(self.folder.name)

    def tearDown(self):
        self.folder.cleanup()

    def run_voca(self, *args):
        return subprocess.run([VOCA, "run", EUROC, "--frames", FRAMES, *map(str, args)], capture_output=True, text=True)

    def test_every_pose_recorded(self):
        done = self.run_voca("-o", self.dir / "traj.tum", "--mcap", self.dir / "rec.mcap")
        self.assertEqual(done.returncode, 0, done.stderr)
        recording = mcap_reader.read_file(self.dir / "rec.mcap")
        self.assertTrue(recording.closed)
        topics = {c.topic for c in recording.channels.values()}
        for topic in ("/voca/pose", "/tf", "/voca/path", "/voca/stats", "/voca/camera/left/compressed"):
            self.assertIn(topic, topics)
        rows = tum_rows(self.dir / "traj.tum")
        self.assertEqual(len(rows), int(FRAMES))
        poses = poses_of(recording)
        # Lost frames repeat the held pose in the file; every frame's pose is in the recording.
        self.assertEqual(set(poses), set(rows))
        for t_ns, row in rows.items():
            self.assertEqual(poses[t_ns], row, f"pose at {t_ns}")
        self.assertEqual(recording.statistics.message_count, len(recording.messages))

    def test_sigint_leaves_a_closed_file(self):
        trajectory, mcap = self.dir / "traj.tum", self.dir / "rec.mcap"
        process = subprocess.Popen([VOCA, "run", EUROC, "--realtime", "-o", trajectory, "--mcap", mcap],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while (not trajectory.exists() or len(tum_rows(trajectory)) < 5) and time.monotonic() < deadline:
            time.sleep(0.1)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
        self.assertEqual(process.returncode, 130, stderr)
        recording = mcap_reader.read_file(mcap)
        self.assertTrue(recording.closed)
        rows = tum_rows(trajectory)
        self.assertGreaterEqual(len(rows), 5)
        self.assertEqual(poses_of(recording), rows)

    def test_full_disk_is_a_warning_not_a_failure(self):
        plain = self.run_voca("-o", self.dir / "plain.tum")
        self.assertEqual(plain.returncode, 0, plain.stderr)
        full = self.run_voca("-o", self.dir / "full.tum", "--mcap", "/dev/full")
        self.assertEqual(full.returncode, 0, full.stderr)
        self.assertIn("/dev/full", full.stderr)
        self.assertIn("warning", full.stderr)
        self.assertEqual((self.dir / "plain.tum").read_bytes(), (self.dir / "full.tum").read_bytes())

    def test_unwritable_path_is_bad_input(self):
        done = self.run_voca("-o", self.dir / "traj.tum", "--mcap", "/nonexistent/folder/rec.mcap")
        self.assertEqual(done.returncode, 1, done.stderr)
        self.assertIn("/nonexistent/folder/rec.mcap", done.stderr)
        self.assertFalse((self.dir / "traj.tum").exists())


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--voca", required=True)
    parser.add_argument("--data", required=True)
    known, rest = parser.parse_known_args()
    VOCA = known.voca
    EUROC = str(pathlib.Path(known.data) / "euroc_v101_micro" / "mav0")
    if not pathlib.Path(EUROC).is_dir():
        print(f"skipped: {EUROC} not found")
        sys.exit(77)
    unittest.main(argv=[sys.argv[0], *rest], verbosity=2)
