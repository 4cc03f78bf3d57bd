#!/usr/bin/env python3
"""The built-in page of `voca run --view` in headless chromium during a live-rate run: once frames have
arrived, a screenshot must show the camera image, the path (and the ground truth) and the latency graph
drawn, not the panels' empty background. The screenshot is kept as view_page.png in the cache folder.

    test_view_page.py <voca binary> <cache folder>
"""

import asyncio
import base64
import io
import json
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import urllib.request

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import view_support  # noqa: E402

try:
    import websockets
    from PIL import Image
except ImportError as missing:
    view_support.skip_or_fail(f"{missing.name} is missing (tools/setup.sh installs python3-websockets, python3-pil)")

VOCA = sys.argv[1] if len(sys.argv) > 1 else "voca"
CACHE = pathlib.Path(sys.argv[2] if len(sys.argv) > 2 else "view-test-data")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    view_support.skip_or_fail("chromium is missing (tools/setup.sh installs it)")

PANEL = (0x1e, 0x21, 0x28)  # the page's panel background
ESTIMATE = (0x4f, 0xc3, 0xf7)
GROUND_TRUTH = (0xef, 0x53, 0x50)
END_TO_END = (0xec, 0xef, 0xf1)


def near(pixel, colour, tolerance=40):
    return all(abs(a - b) <= tolerance for a, b in zip(pixel[:3], colour))


class Chromium:
    """Headless chromium on a page, driven over the DevTools protocol."""

    def __init__(self, url, profile):
        self.proc = subprocess.Popen(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={profile}", "--window-size=1280,800", "--hide-scrollbars",
             "--remote-debugging-port=0", url],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.lines = []
        found = threading.Event()
        self.devtools = None

        def read():
            for line in self.proc.stderr:
                self.lines.append(line)
                match = re.search(r"DevTools listening on (ws://\S+)", line)
                if match:
                    self.devtools = match.group(1)
                    found.set()
            found.set()

        threading.Thread(target=read, daemon=True).start()
        if not found.wait(60) or self.devtools is None:
            self.close()
            raise AssertionError("chromium did not start:\n" + "".join(self.lines))
        port = re.search(r"ws://[^:/]+:(\d+)/", self.devtools).group(1)
        deadline = time.monotonic() + 30
        while True:
            targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
            pages = [t for t in targets if t["type"] == "page" and t["url"].startswith(url)]
            if pages:
                self.page = pages[0]["webSocketDebuggerUrl"]
                break
            if time.monotonic() > deadline:
                raise AssertionError(f"no page for {url} among {targets}")
            time.sleep(0.5)

    def close(self):
        self.proc.kill()
        self.proc.wait()


async def call(ws, counter, method, params=None):
    counter[0] += 1
    await ws.send(json.dumps({"id": counter[0], "method": method, "params": params or {}}))
    while True:
        reply = json.loads(await ws.recv())
        if reply.get("id") == counter[0]:
            if "error" in reply:
                raise AssertionError(f"{method}: {reply['error']}")
            return reply["result"]


async def evaluate(ws, counter, expression):
    result = await call(ws, counter, "Runtime.evaluate", {"expression": expression, "returnByValue": True})
    return result["result"].get("value")


async def screenshot_after_frames(page):
    """(screenshot PNG bytes, {element: rect}, progress) once images, paths and statistics arrived."""
    counter = [0]
    async with websockets.connect(page, max_size=None) as ws:
        progress = None
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            progress = await evaluate(ws, counter, "window.vocaView ? JSON.stringify({frames: vocaView.framesReceived, "
                                                   "images: vocaView.imagesReceived, paths: vocaView.pathsReceived, "
                                                   "truth: vocaView.groundTruth.length, "
                                                   "status: document.getElementById('status').textContent}) : null")
            progress = json.loads(progress) if progress else None
            if progress and progress["frames"] >= 30 and progress["images"] >= 5 and progress["paths"] >= 5 \
                    and progress["truth"] >= 2:
                break
            await asyncio.sleep(0.25)
        await asyncio.sleep(0.5)  # one more frame of drawing
        rects = json.loads(await evaluate(ws, counter, "JSON.stringify(Object.fromEntries(['image', 'path', 'latency']"
                                                       ".map(id => { const r = document.getElementById(id)"
                                                       ".getBoundingClientRect(); return [id, [r.left, r.top, r.right, "
                                                       "r.bottom]]; })))"))
        ratio = await evaluate(ws, counter, "window.devicePixelRatio")
        shot = await call(ws, counter, "Page.captureScreenshot", {"format": "png"})
        return base64.b64decode(shot["data"]), rects, ratio, progress


class PageTest(unittest.TestCase):
    def test_page_draws_image_path_and_latency(self):
        video = view_support.sequence(VOCA, CACHE)
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            # Half speed: 8 s of frames, time for the browser to start and connect on a loaded machine.
            run = view_support.Run([VOCA, "run", str(video), "-o", str(tmp / "t.txt"), "--realtime", "--speed", "0.5",
                                    "--view", "127.0.0.1:0"])
            port = run.wait_port()
            (tmp / "profile").mkdir()
            browser = Chromium(f"http://127.0.0.1:{port}/", tmp / "profile")
            try:
                png, rects, ratio, progress = asyncio.run(screenshot_after_frames(browser.page))
            finally:
                browser.close()
            self.assertEqual(run.finish(), 0, run.stderr())
        self.assertIsNotNone(progress, "the page's script did not run")
        self.assertGreaterEqual(progress["images"], 5, progress)
        self.assertTrue(progress["status"].startswith("frame "), progress["status"])
        CACHE.mkdir(parents=True, exist_ok=True)
        (CACHE / "view_page.png").write_bytes(png)
        image = Image.open(io.BytesIO(png)).convert("RGB")

        def region(name):
            left, top, right, bottom = (round(v * ratio) for v in rects[name])
            crop = image.crop((left + 2, top + 2, right - 2, bottom - 2))
            return list(crop.getdata())

        camera = region("image")
        drawn = sum(1 for p in camera if not near(p, PANEL, 6)) / len(camera)
        self.assertGreater(drawn, 0.4, f"the image area is mostly background ({drawn:.0%} drawn)")
        self.assertGreater(len(set(camera)), 200, "the image area has too few colours to be a camera picture")
        path = region("path")
        self.assertGreater(sum(1 for p in path if near(p, ESTIMATE)), 40, "no estimated path in the top view")
        self.assertGreater(sum(1 for p in path if near(p, GROUND_TRUTH)), 20, "no ground truth in the top view")
        latency = region("latency")
        self.assertGreater(sum(1 for p in latency if near(p, END_TO_END, 12)), 40, "no end-to-end latency line")


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
