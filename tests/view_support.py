"""Shared by the live view's end-to-end tests (test_view.py, test_view_page.py): a short rendered and
encoded sequence made once per build folder, `voca run --view` started in the background with the URL it
prints, and a minimal Foxglove WebSocket client."""

import fcntl
import json
import os
import pathlib
import re
import struct
import subprocess
import sys
import threading
import time

SKIP = 77  # CTest's skip code (tests/CMakeLists.txt); with CI=true a missing dependency fails instead


def skip_or_fail(reason):
    print(f"skipped: {reason}", file=sys.stderr)
    sys.exit(1 if os.environ.get("CI") == "true" else SKIP)


def sequence(voca, cache):
    """A 4 s stereo video with ground truth (`voca synth` + `voca encode`), made once in `cache`; a lock
    lets the view tests share it when CTest runs them in parallel."""
    cache = pathlib.Path(cache)
    cache.mkdir(parents=True, exist_ok=True)
    video = cache / "video"
    with open(cache / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (video / "mav0" / "cam1" / "data.mp4").exists():
            subprocess.run([voca, "synth", "--out", str(cache / "raw"), "--motion", "fast-rotation", "--seconds", "4",
                            "--supersample", "1"], check=True, stdout=subprocess.DEVNULL)
            subprocess.run([voca, "encode", str(cache / "raw"), "--out", str(video), "--bitrate", "500k"], check=True,
                           stdout=subprocess.DEVNULL)
    return video


class Run:
    """A `voca` command in the background; stderr is read continuously (lines kept) so the pipe never
    fills, and the view's URL is taken from the line it prints."""

    URL = re.compile(r"^view: http://([^/]+):(\d+)/ \(Foxglove: ws://")

    def __init__(self, args):
        self.started = time.monotonic()
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.lines = []
        self.port = None
        self._have_port = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.peak_rss_kb = 0
        self._sampling = True
        self._sampler = threading.Thread(target=self._sample, daemon=True)
        self._sampler.start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))
            match = self.URL.match(line)
            if match and self.port is None:
                self.port = int(match.group(2))
                self._have_port.set()
        self._have_port.set()

    def _sample(self):
        while self._sampling and self.proc.poll() is None:
            self.peak_rss_kb = max(self.peak_rss_kb, self.rss_kb())
            time.sleep(0.05)

    def rss_kb(self):
        try:
            with open(f"/proc/{self.proc.pid}/status") as status:
                for line in status:
                    if line.startswith("VmRSS:"):
                        return int(line.split()[1])
        except OSError:
            pass
        return 0

    def wait_port(self, timeout=60):
        if not self._have_port.wait(timeout) or self.port is None:
            self.proc.kill()
            raise AssertionError("no 'view: http://...' line; stderr:\n" + "\n".join(self.lines))
        return self.port

    def finish(self, timeout=120):
        stdout = self.proc.stdout.read()  # stderr is the reader thread's
        self.proc.wait(timeout=timeout)
        self._reader.join(5)
        self.proc.stdout.close()
        self.proc.stderr.close()
        self._sampling = False
        self.seconds = time.monotonic() - self.started
        self.stdout = stdout
        return self.proc.returncode

    def stderr(self):
        return "\n".join(self.lines)


def parse_message_data(frame):
    """(subscription id, timestamp ns, decoded JSON) of a binary message data frame."""
    opcode, subscription, timestamp = struct.unpack_from("<BIQ", frame, 0)
    assert opcode == 1, f"opcode {opcode}"
    return subscription, timestamp, json.loads(frame[13:].decode())
