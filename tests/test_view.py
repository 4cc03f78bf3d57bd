#!/usr/bin/env python3
"""`voca run --view` end to end, at the protocol level: a Foxglove WebSocket client during a real
live-rate run checks serverInfo, the advertised channels and their JSON Schemas, subscribes, decodes the
binary message frames and compares the poses with the trajectory file the same run wrote; the trajectory
equals a run's without --view. Bad input: a port in use, clients that send garbage or hang up
mid-frame, and a client that never reads (the run ends on time, memory stays bounded).

    test_view.py <voca binary> <cache folder>
"""

import asyncio
import base64
import json
import math
import os
import pathlib
import socket
import struct
import sys
import tempfile
import time
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import view_support  # noqa: E402

try:
    import jsonschema
    import websockets
except ImportError as missing:
    view_support.skip_or_fail(f"{missing.name} is missing (tools/setup.sh installs python3-websockets and "
                              "python3-jsonschema)")

VOCA = sys.argv[1] if len(sys.argv) > 1 else "voca"
CACHE = sys.argv[2] if len(sys.argv) > 2 else "view-test-data"
SUBPROTOCOL = "foxglove.websocket.v1"
CHANNELS = {
    "/voca/camera/left/compressed": "foxglove.CompressedImage",
    "/voca/camera/left/motion_vectors": "foxglove.ImageAnnotations",
    "/voca/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/voca/path": "foxglove.PosesInFrame",
    "/voca/ground_truth/path": "foxglove.PosesInFrame",
    "/voca/landmarks": "foxglove.PointCloud",
    "/voca/stats": "voca.FrameStats",
}


def read_tum(path):
    """{t_ns: [tx, ty, tz, qx, qy, qz, qw]} with the file's numbers as floats."""
    rows = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        fields = line.split()
        seconds, fraction = fields[0].split(".")
        rows[int(seconds) * 1_000_000_000 + int(fraction)] = [float(v) for v in fields[1:]]
    return rows


def handshake(port, rcvbuf=None, protocol=SUBPROTOCOL):
    """A WebSocket connection made by hand (for clients that misbehave below the library's level)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    if rcvbuf:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    sock.connect(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                  f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                  f"Sec-WebSocket-Protocol: {protocol}\r\n\r\n").encode())
    reply = b""
    while b"\r\n\r\n" not in reply:
        chunk = sock.recv(1)
        assert chunk, "closed during the handshake"
        reply += chunk
    assert reply.startswith(b"HTTP/1.1 101"), reply
    return sock


def client_frame(opcode, payload, fin=True):
    """A masked client frame (RFC 6455: every client frame is masked)."""
    header = bytes([(0x80 if fin else 0) | opcode])
    n = len(payload)
    if n < 126:
        header += bytes([0x80 | n])
    elif n < 65536:
        header += bytes([0x80 | 126]) + struct.pack(">H", n)
    else:
        header += bytes([0x80 | 127]) + struct.pack(">Q", n)
    mask = os.urandom(4)
    return header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def read_server_frame(sock):
    """(opcode, payload) of one unmasked server frame."""
    def exactly(n):
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise ConnectionError("closed")
            data += chunk
        return data
    first, second = exactly(2)
    n = second & 0x7F
    if n == 126:
        n = struct.unpack(">H", exactly(2))[0]
    elif n == 127:
        n = struct.unpack(">Q", exactly(8))[0]
    return first & 0x0F, exactly(n)


# The live rate the runs replay at, as a factor of the recording's. Equal trajectories need runs that
# keep up without dropping frames: a sanitizer build, several times slower, replays slower
# (VOCA_TEST_REPLAY_SPEED, set by tests/view.cmake).
SPEED = os.environ.get("VOCA_TEST_REPLAY_SPEED", "1")


class ViewTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.video = view_support.sequence(VOCA, CACHE)
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = pathlib.Path(cls.tmp.name)
        # The reference: the same input without --view, at the same live rate.
        cls.plain = cls.dir / "plain.txt"
        plain = view_support.Run([VOCA, "run", str(cls.video), "-o", str(cls.plain), "--realtime", "--speed",
                                  SPEED])
        assert plain.finish() == 0, plain.stderr()
        cls.plain_seconds = plain.seconds
        cls.plain_peak_rss_kb = plain.peak_rss_kb

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def start(self, name, *extra, speed=1.0):
        """A --view run at `speed` times the live rate of the reference run."""
        trajectory = self.dir / f"{name}.txt"
        run = view_support.Run([VOCA, "run", str(self.video), "-o", str(trajectory), "--realtime",
                                "--speed", str(float(SPEED) * speed), "--view", "127.0.0.1:0", *extra])
        run.wait_port()
        return run, trajectory

    def assert_same_trajectory(self, trajectory):
        self.assertEqual(trajectory.read_bytes(), self.plain.read_bytes(),
                         "the trajectory with --view differs from the one without")

    def test_protocol_channels_and_poses(self):
        run, trajectory = self.start("protocol")
        received = asyncio.run(self.subscribe_all(run.port))
        self.assertEqual(run.finish(), 0, run.stderr())
        self.assert_same_trajectory(trajectory)

        info, channels, messages = received
        self.assertEqual(info["op"], "serverInfo")
        self.assertEqual(info["name"], "voca")
        self.assertIn("parameters", info["capabilities"])
        self.assertEqual({c["topic"]: c["schemaName"] for c in channels.values()}, CHANNELS)
        validators = {}
        for channel in channels.values():
            self.assertEqual(channel["encoding"], "json")
            self.assertEqual(channel["schemaEncoding"], "jsonschema")
            schema = json.loads(channel["schema"])
            jsonschema.Draft7Validator.check_schema(schema)  # a well-formed JSON Schema
            self.assertEqual(schema["title"], channel["schemaName"])
            validators[channel["topic"]] = jsonschema.Draft7Validator(schema)
        by_topic = {topic: [] for topic in CHANNELS}
        for topic, timestamp, message in messages:
            validators[topic].validate(message)
            if "timestamp" in message:
                stamp = message["timestamp"]
                self.assertEqual(stamp["sec"] * 1_000_000_000 + stamp["nsec"], timestamp, topic)
            by_topic[topic].append((timestamp, message))

        # Every pose received is a row of the trajectory file: same time, same numbers to its last digit.
        rows = read_tum(trajectory)
        poses = by_topic["/voca/pose"]
        self.assertGreaterEqual(len(poses), len(rows) // 2, "too few poses arrived")
        for timestamp, message in poses:
            self.assertIn(timestamp, rows)
            p, q = message["pose"]["position"], message["pose"]["orientation"]
            self.assertEqual([p["x"], p["y"], p["z"], q["x"], q["y"], q["z"], q["w"]], rows[timestamp])
            self.assertEqual(message["frame_id"], "odom")
        for timestamp, message in by_topic["/tf"]:
            self.assertEqual((message["parent_frame_id"], message["child_frame_id"]), ("odom", "base_link"))
            self.assertEqual(message["translation"]["x"], rows[timestamp][0])

        # The path so far ends at the pose of its time; the ground truth (synth has one) comes along.
        paths = by_topic["/voca/path"]
        self.assertGreaterEqual(len(paths), 2)
        timestamp, last_path = paths[-1]
        end = last_path["poses"][-1]["position"]
        self.assertEqual([end["x"], end["y"], end["z"]], rows[timestamp][:3])
        # The path starts at the run's first pose, although the client connected after it.
        first = rows[min(rows)]
        start = last_path["poses"][0]
        self.assertEqual([start["position"]["x"], start["position"]["y"], start["position"]["z"]], first[:3])
        # It holds every pose up to its time, also those from before the client connected.
        self.assertGreaterEqual(len(last_path["poses"]), len([t for t, _ in poses if t <= timestamp]))
        truth = by_topic["/voca/ground_truth/path"]
        self.assertGreaterEqual(len(truth), 2)
        self.assertEqual(len(truth[-1][1]["poses"]), len(paths[-1][1]["poses"]))
        # The estimate is accurate on this clean sequence, so the aligned ground truth stays close to it.
        gt_end = truth[-1][1]["poses"][-1]["position"]
        self.assertLess(math.dist([gt_end["x"], gt_end["y"], gt_end["z"]], [end["x"], end["y"], end["z"]]), 0.1)

        images = by_topic["/voca/camera/left/compressed"]
        self.assertGreaterEqual(len(images), 5)
        for _, image in images:
            self.assertEqual(image["format"], "jpeg")
            self.assertEqual(base64.b64decode(image["data"])[:2], b"\xff\xd8")
        vectors = by_topic["/voca/camera/left/motion_vectors"]
        self.assertGreaterEqual(len(vectors), 5)
        self.assertTrue(any(len(v["points"][0]["points"]) > 10 for _, v in vectors), "no motion vectors drawn")

        clouds = by_topic["/voca/landmarks"]
        self.assertGreaterEqual(len(clouds), 2)
        data = base64.b64decode(clouds[-1][1]["data"])
        points = [struct.unpack_from("<fff", data, 12 * i) for i in range(len(data) // 12)]
        self.assertGreater(len(points), 20)
        self.assertTrue(all(all(math.isfinite(v) for v in p) for p in points))

        stats = [m for _, m in by_topic["/voca/stats"]]
        self.assertGreaterEqual(len(stats), len(rows) // 2)
        frames = [s["frame"] for s in stats]
        self.assertEqual(frames, sorted(frames))
        self.assertTrue(all(s["latency_ms"]["frontend"] > 0 and s["latency_ms"]["end_to_end"] > 0 for s in stats))
        self.assertTrue(all(s["tracks"]["left"] > 0 for s in stats))
        self.assertIn("closed: 1 client session", run.stderr())

    async def subscribe_all(self, port):
        """serverInfo, {id: channel}, [(topic, timestamp, message)] until the server closes at the end."""
        messages = []
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL], max_size=None) as ws:
            self.assertEqual(ws.subprotocol, SUBPROTOCOL)
            info = json.loads(await ws.recv())
            advertise = json.loads(await ws.recv())
            self.assertEqual(advertise["op"], "advertise")
            channels = {c["id"]: c for c in advertise["channels"]}
            topic_of = {}
            subscriptions = []
            for n, channel in enumerate(channels.values()):
                topic_of[100 + n] = channel["topic"]
                subscriptions.append({"id": 100 + n, "channelId": channel["id"]})
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            try:
                while True:
                    frame = await ws.recv()
                    self.assertIsInstance(frame, bytes, f"unexpected text: {frame}")
                    subscription, timestamp, message = view_support.parse_message_data(frame)
                    messages.append((topic_of[subscription], timestamp, message))
            except websockets.ConnectionClosed:
                self.assertEqual(ws.close_code, 1001)  # going away: the run ended
        return info, channels, messages

    def test_port_in_use(self):
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen()
            port = taken.getsockname()[1]
            trajectory = self.dir / "in_use.txt"
            run = view_support.Run([VOCA, "run", str(self.video), "-o", str(trajectory), "--view",
                                    f"127.0.0.1:{port}"])
            self.assertEqual(run.finish(), 1)
        self.assertIn(f"cannot serve the view on 127.0.0.1:{port}: Address already in use", run.stderr())
        self.assertIn("choose another port (port 0 picks a free one)", run.stderr())
        self.assertFalse(trajectory.exists(), "a trajectory was written although the run never started")
        self.assertLess(run.seconds, 10)
        bad = view_support.Run([VOCA, "run", str(self.video), "-o", str(trajectory), "--view", "localhost:99999"])
        self.assertEqual(bad.finish(), 1)
        self.assertIn("\"localhost:99999\": the port is above 65535", bad.stderr())
        self.assertFalse(trajectory.exists())

    def test_garbage_clients(self):
        run, trajectory = self.start("garbage")
        port = run.port
        replies = asyncio.run(self.send_garbage(port))
        # Below the library: half a frame then hang up; bytes that are no HTTP at all; a huge message.
        half = handshake(port)
        half.sendall(client_frame(0x1, b'{"op": "subscribe", "subscriptions": []}')[:9])
        half.close()
        junk = socket.create_connection(("127.0.0.1", port))
        junk.sendall(os.urandom(3000))
        junk.close()
        big = handshake(port)
        big.sendall(client_frame(0x1, b"x" * 200_000))
        opcode, payload = read_server_frame(big)
        while opcode != 0x8:  # serverInfo and advertise first, then the close
            opcode, payload = read_server_frame(big)
        self.assertEqual(struct.unpack(">H", payload[:2])[0], 1009)  # message too big
        big.close()
        self.assertEqual(run.finish(), 0, run.stderr())
        self.assert_same_trajectory(trajectory)

        statuses, parameters, stats_after, spammer_close = replies
        self.assertGreaterEqual(len(statuses), 9)
        self.assertTrue(all(s["level"] == 2 for s in statuses))
        self.assertEqual(parameters["parameters"][0]["name"], "image_rate_hz")
        self.assertEqual(parameters["id"], "p1")
        self.assertGreater(stats_after, 5, "the client that sent garbage got no data afterwards")
        self.assertEqual(spammer_close, 1008)  # policy violation: too many invalid requests
        log = run.stderr()
        self.assertIn("a request that is not a JSON object", log)
        self.assertIn("disconnected after 20 refused requests", log)

    async def send_garbage(self, port):
        url = f"ws://127.0.0.1:{port}"
        async with websockets.connect(url, subprotocols=[SUBPROTOCOL], max_size=None) as ws:
            await ws.recv()
            channels = {c["topic"]: c["id"] for c in json.loads(await ws.recv())["channels"]}
            stats = channels["/voca/stats"]
            garbage = [
                "not json at all {",
                "[1, 2, 3]",
                json.dumps({"op": 5}),
                json.dumps({"op": "fly"}),
                b"\x01\x02\x03binary junk",
                json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 999}]}),
                json.dumps({"op": "subscribe", "subscriptions": "all"}),
                json.dumps({"op": "subscribe", "subscriptions": [{"id": -4, "channelId": stats}]}),
                json.dumps({"op": "unsubscribe", "subscriptionIds": [77]}),
                json.dumps({"op": "setParameters", "parameters": [{"name": "image_rate_hz", "value": 1e9}]}),
            ]
            for message in garbage:
                await ws.send(message)
            await ws.send(json.dumps({"op": "getParameters", "parameterNames": [], "id": "p1"}))
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": stats}]}))
            statuses, parameters, stats_after = [], None, 0
            try:
                while stats_after < 10:
                    frame = await asyncio.wait_for(ws.recv(), 20)
                    if isinstance(frame, str):
                        reply = json.loads(frame)
                        if reply["op"] == "status":
                            statuses.append(reply)
                        elif reply["op"] == "parameterValues":
                            parameters = reply
                    else:
                        subscription, _, _ = view_support.parse_message_data(frame)
                        self.assertEqual(subscription, 7)
                        stats_after += 1
            except websockets.ConnectionClosed:
                pass
        # A client that keeps sending garbage is disconnected.
        async with websockets.connect(url, subprotocols=[SUBPROTOCOL]) as spammer:
            try:
                # Exactly the server's limit: more would still be unread when it hangs up, and a socket
                # closed with unread data resets the connection (1006) before the close frame is read.
                for _ in range(20):
                    await spammer.send("{broken")
                while True:
                    await asyncio.wait_for(spammer.recv(), 20)
            except websockets.ConnectionClosed:
                pass
            spammer_close = spammer.close_code
        return statuses, parameters, stats_after, spammer_close

    def test_slow_client_never_reads(self):
        # Half speed: 8 s of images at 30 Hz, far more than the server holds back for one client.
        run, trajectory = self.start("slow", speed=0.5)
        sock = handshake(run.port, rcvbuf=4096)
        read_server_frame(sock)  # serverInfo
        _, advertise = read_server_frame(sock)
        channels = json.loads(advertise)["channels"]
        sock.sendall(client_frame(0x1, json.dumps({"op": "setParameters", "parameters": [
            {"name": "image_rate_hz", "value": 30}]}).encode()))
        sock.sendall(client_frame(0x1, json.dumps({"op": "subscribe", "subscriptions": [
            {"id": c["id"], "channelId": c["id"]} for c in channels]}).encode()))
        # ... and never reads again.
        code = run.finish()
        sock.close()
        self.assertEqual(code, 0, run.stderr())
        self.assert_same_trajectory(trajectory)
        log = run.stderr()
        self.assertIn("reads too slowly: its messages are dropped", log)
        dropped = int(log.split(" dropped for slow clients")[0].rsplit(" ", 1)[1])
        self.assertGreater(dropped, 0)
        # On time: as long as the half-speed run takes, plus at most the server's one second to give up on
        # the client at the end (and some noise of this shared machine).
        self.assertLess(run.seconds, 2 * self.plain_seconds + 4.0)
        # Bounded: the server holds back at most 4 MiB of messages per client, and as much again in the batch
        # it is writing when the client stops reading; the rest is the messages' own overhead and the ring.
        # ASan keeps freed blocks in quarantine instead of reusing them, so there peak memory follows how
        # much was allocated, not how much is held.
        growth_mb = (run.peak_rss_kb - self.plain_peak_rss_kb) / 1024
        if os.environ.get("VOCA_TEST_SANITIZER") != "address":
            self.assertLess(growth_mb, 32, f"the peak memory grew by {growth_mb:.0f} MB with a client that never reads")


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
