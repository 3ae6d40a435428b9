#!/usr/bin/python3
"""End-to-end tests of `nephele serve`: the real daemon on port 0, driven over the socket
protocol, pymodbus and mbpoll. Readiness is the daemon's ready line, never a sleep.

Run by ctest with NEPHELE_BINARY and NEPHELE_SOURCE_DIR set; /usr/bin/python3 (Debian's,
which has pymodbus)."""
import json
import math
import os
import re
import signal
import socket
import struct
import subprocess
import tempfile
import threading
import time
import unittest
import zlib

BINARY = os.environ.get("NEPHELE_BINARY", "build/nephele")
SOURCE = os.environ.get("NEPHELE_SOURCE_DIR", ".")
SCENE = os.path.join(SOURCE, "config", "scenes", "cumulus.toml")
TIMEOUT = 60  # seconds any single wait may take (sanitizer builds are slow)
TIME_FACTOR = float(os.environ.get("NEPHELE_TIME_FACTOR", "1"))  # 10 under the sanitizers


# The live fuzz's daemon (live_fuzz.py): frames of at most 65,536 pixels and 2 subscriptions.
# A render's work grows with its pixels: on two cores under llvmpipe a heavy sky costs about
# 4 us a pixel, and the label channels traced on the CPU (cloud_depth, lwir, glint) about 20, so
# 0.25 MiP took 5.6 s. A lockstep tick renders every subscription's frame before anything else
# runs; these limits keep it, and every other reply, within the fuzz's 5 s bound. Snapshots only
# when asked and at shutdown. It prewarms, as a cockpit's daemon does, but under the
# sanitizers, whose bounds are ten times wider and whose prewarm would take minutes.
LIVE_FUZZ_DAEMON = dict(socket_keys="max_pending_mb = 4\nmax_image_pixels = 0.0625\n"
                                    "max_subscriptions = 2",
                        world_keys="prewarm = " + ("true" if TIME_FACTOR == 1 else "false"),
                        extra="[snapshot]\npath = \"{snapshot}\"\ninterval = 0\n")


def wait_until(condition, what, timeout=TIMEOUT):
    """Polls `condition` until it holds; fails the test with `what` after `timeout`."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    raise AssertionError("timed out waiting for " + what)


class Daemon:
    """A `nephele serve` process with its own config in a temporary directory."""

    def __init__(self, workdir, mode="lockstep", extra="", view_size=(64, 48), name="d",
                 socket_keys="", modbus_keys="", scene=SCENE, frames=None, env=None,
                 world_keys=""):
        """`extra` is appended to the config ({snapshot} becomes this daemon's snapshot
        path); `world_keys`, `socket_keys` and `modbus_keys` go into those tables. A test
        daemon starts without [world] prewarm unless world_keys sets it: most tests do not
        time frames, and the prewarm's seconds would repeat at every start."""
        if "prewarm" not in world_keys:
            world_keys += "\nprewarm = false"
        self.workdir = workdir
        self.env = dict(os.environ, **(env or {}))
        self.config = os.path.join(workdir, name + ".toml")
        self.log_path = os.path.join(workdir, name + ".log")
        self.snapshot = os.path.join(workdir, name + "-snap", "world.snap")
        with open(self.config, "w") as f:
            f.write(f'''scene = "{scene}"
[world]
mode = "{mode}"
tick_rate = 30
{world_keys}
[[view]]
name = "front"
width = {view_size[0]}
height = {view_size[1]}
[[view]]
name = "left"
heading = -60.0
width = 32
height = 24
format = "png"
[socket]
port = 0
{socket_keys}
[modbus]
port = 0
{modbus_keys}
[metrics]
enabled = true
port = 0
[output]
directory = "{frames or os.path.join(workdir, name + "-frames")}"
{extra.format(snapshot=self.snapshot)}
''')
        self.start()

    def start(self):
        self.clients = []
        self.log = open(self.log_path, "a")
        self.proc = subprocess.Popen([BINARY, "serve", "-c", self.config], env=self.env,
                                     stdout=subprocess.PIPE, stderr=self.log, text=True)
        line = self.proc.stdout.readline()  # blocks until ready, or EOF if the start failed
        if not line.startswith("nephele ready"):
            self.proc.wait(TIMEOUT)
            raise AssertionError("daemon did not start: " + open(self.log_path).read())
        self.ports = {k: int(v) for k, v in (kv.split("=") for kv in line.split()[2:])}
        self.port, self.modbus_port, self.metrics_port = (
            self.ports["socket"], self.ports["modbus"], self.ports["metrics"])

    def stop(self, sig=signal.SIGTERM):
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        code = self.proc.wait(TIMEOUT)
        for c in self.clients:
            c.close()
        self.proc.stdout.close()
        self.log.close()
        return code

    def client(self):
        c = Client(self.port)
        self.clients.append(c)
        return c

    def log_text(self):
        with open(self.log_path) as f:
            return f.read()


def read_message(file):
    """One reply or event from a connection's file: (header, image bytes or None)."""
    line = file.readline()
    if not line:
        raise ConnectionError("connection closed")
    header = json.loads(line)
    image = (header.get("result") or {}).get("image") or header.get("image")
    body = file.read(image["bytes"]) if isinstance(image, dict) and "bytes" in image else None
    return header, body


class Client:
    def __init__(self, port, receive_buffer=None):
        """`receive_buffer` (bytes) caps what the kernel holds unread for this client."""
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if receive_buffer:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
        self.sock.settimeout(TIMEOUT)
        self.sock.connect(("127.0.0.1", port))
        self.file = self.sock.makefile("rb")
        self.next_id = 1

    def close(self):
        self.file.close()
        self.sock.close()

    def send(self, obj):
        obj = dict(obj)
        if "id" not in obj:
            obj["id"] = self.next_id
            self.next_id += 1
        self.sock.sendall((json.dumps(obj) + "\n").encode())
        return obj["id"]

    def read(self):
        """One reply or event: (header, body bytes or None)."""
        return read_message(self.file)

    def request(self, obj):
        sent = self.send(obj)
        header, body = self.read()
        assert header.get("id") == sent, (header, sent)
        return header, body

    def ok(self, obj):
        header, body = self.request(obj)
        assert header["ok"], header
        return (header["result"], body) if body is not None else header["result"]

    def error(self, obj):
        header, _ = self.request(obj)
        assert not header["ok"], header
        return header["error"]


def decode_png(data):
    """8-bit, non-interlaced PNG to (width, height, channels, rows of bytes); an
    independent decoder to check the daemon's PNG against its raw frame."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour_type = struct.unpack(">IIBB", chunk[:10])
            assert depth == 8
            channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour_type]
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, channels, b"".join(rows)


def floats(value):
    return list(struct.unpack(">HH", struct.pack(">f", value)))


class DaemonTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.daemons = []

    def tearDown(self):
        for d in self.daemons:
            if d.proc.poll() is None:
                d.stop(signal.SIGKILL)
        self.tmp.cleanup()

    def daemon(self, **kwargs):
        d = Daemon(self.tmp.name, **kwargs)
        self.daemons.append(d)
        return d


class SocketProtocolTest(DaemonTest):
    def test_hello_views_and_renders(self):
        d = self.daemon()
        c = d.client()
        hello = c.ok({"cmd": "hello"})
        self.assertEqual(hello["views"], ["front", "left"])
        self.assertEqual(hello["mode"], "lockstep")
        view = c.ok({"cmd": "get_view", "view": "front"})
        self.assertEqual((view["width"], view["height"]), (64, 48))
        # Raw RGBA and PNG of the same world state carry the same pixels.
        meta, raw = c.ok({"cmd": "render", "view": "front", "format": "raw"})
        self.assertEqual(meta["image"]["channels"], ["colour", "coverage"])
        self.assertEqual(len(raw), 64 * 48 * 4)
        meta, png = c.ok({"cmd": "render", "view": "front", "format": "png",
                          "channels": ["colour", "coverage"]})
        self.assertEqual(decode_png(png), (64, 48, 4, raw))
        # Channel selection: colour only drops every fourth byte.
        _, rgb = c.ok({"cmd": "render", "view": "front", "channels": ["colour"]})
        self.assertEqual(rgb, bytes(b for i, b in enumerate(raw) if i % 4 != 3))
        _, jpeg = c.ok({"cmd": "render", "view": "front", "format": "jpeg"})
        self.assertEqual(jpeg[:2], b"\xff\xd8")
        _, exr = c.ok({"cmd": "render", "view": "front", "format": "exr"})
        self.assertEqual(exr[:4], b"\x76\x2f\x31\x01")
        # The cloud is in view: some pixels are covered, some are sky.
        coverage = raw[3::4]
        self.assertGreater(max(coverage), 200)
        self.assertEqual(min(coverage), 0)
        # Ground truth as float32 planes in the order asked, with the camera in the header:
        # visibility is 1 - coverage, depth is finite only below the horizon (the ground).
        meta, planes = c.ok({"cmd": "render", "view": "front",
                             "channels": ["visibility", "depth", "coverage"]})
        image = meta["image"]
        self.assertEqual(image["encoding"], "float32-planes")
        self.assertEqual(image["channels"], ["visibility", "depth", "coverage"])
        self.assertAlmostEqual(image["camera"]["focal_px"],
                               24 / math.tan(math.radians(view["vfov"] / 2)), places=6)
        self.assertEqual(image["camera"]["principal_point"], [32.0, 24.0])
        self.assertEqual(len(planes), 64 * 48 * 4 * 3)
        n = 64 * 48
        values = struct.unpack("<%df" % (3 * n), planes)
        visibility, depth, cover = values[:n], values[n:2 * n], values[2 * n:]
        self.assertTrue(all(abs(v + c - 1.0) < 1e-6 for v, c in zip(visibility, cover)))
        self.assertTrue(all(math.isinf(d) or d > 0 for d in depth))
        self.assertTrue(any(math.isinf(d) for d in depth[:64]))  # sky in the top row
        _, exr = c.ok({"cmd": "render", "view": "front", "format": "exr",
                       "channels": ["colour", "object_id"]})
        self.assertEqual(exr[:4], b"\x76\x2f\x31\x01")
        self.assertIn(b"object_id", exr[:2000])

    def test_fog_and_haze_with_no_field_are_read_back_unchanged(self):
        c = self.daemon().client()
        hash_before = c.ok({"cmd": "hash"})["hash"]
        self.assertEqual(c.ok({"cmd": "set_fog"}), {"enabled": False})
        self.assertEqual(c.ok({"cmd": "set_haze"}), {"enabled": False})
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], hash_before)
        self.assertTrue(c.ok({"cmd": "set_haze", "enabled": True})["enabled"])
        self.assertTrue(c.ok({"cmd": "set_haze"})["enabled"])

    def test_set_view_changes_the_frame(self):
        d = self.daemon()
        c = d.client()
        _, before = c.ok({"cmd": "render", "view": "front"})
        result = c.ok({"cmd": "set_view", "view": "front", "heading": 180.0, "width": 40})
        self.assertEqual((result["heading"], result["width"]), (180.0, 40))
        meta, after = c.ok({"cmd": "render", "view": "front"})
        self.assertEqual(meta["image"]["width"], 40)
        self.assertEqual(max(after[3::4]), 0)  # looking away from the cloud: no coverage

    def test_errors_name_the_field_and_change_nothing(self):
        d = self.daemon()
        c = d.client()
        before = c.ok({"cmd": "hash"})["hash"]
        cases = [
            ({"cmd": "nonsense"}, "unknown_command", "allowed: hello"),
            ({"cmd": "set_view", "view": "front", "vfov": 500}, "bad_field", "vfov"),
            ({"cmd": "set_view", "view": "front", "pitch": "up"}, "bad_field", "pitch"),
            ({"cmd": "set_view", "view": "nowhere"}, "not_found", "front, left"),
            ({"cmd": "set_weather", "layer": 1, "type": 11}, "bad_field", "0 to 10"),
            ({"cmd": "set_weather", "layer": 4, "type": 1}, "bad_field", "layer"),
            ({"cmd": "set_weather", "layer": 1, "type": 7, "coverage": -5}, "bad_field",
             "coverage"),
            ({"cmd": "set_weather", "layer": 1, "type": 10, "scud": 150}, "bad_field", "scud"),
            ({"cmd": "render", "view": "front", "format": "gif"}, "bad_field", "raw, png"),
            ({"cmd": "render", "view": "front", "format": "png", "channels": ["depth"]},
             "bad_field", "format raw or exr only"),
            ({"cmd": "render", "view": "front", "channels": ["height"]}, "bad_field",
             "allowed: a non-empty array of colour, coverage, depth, cloud_depth"),
            ({"cmd": "render", "view": "front", "format": "jpeg", "channels": ["coverage"]},
             "bad_field", "jpeg"),
            ({"cmd": "tick", "dt": -1}, "bad_field", "dt"),
            # One edge for every reader (world/limits.h): the World's own limit on one advance.
            ({"cmd": "set_time", "advance": 2e7, "paused": True}, "bad_field",
             "advance: 2e+07 is out of range (allowed: 0 to 1e+07)"),
            ({"cmd": "tick"}, "bad_field", "dt: is missing"),
            ({"cmd": "add_cloud", "cloud": {"name": "x", "ellipsoid": [{"radii": [0, 1, 1]}]}},
             "bad_field", "radii"),
            ({"cmd": "add_cloud", "cloud": {"cumulus": {}}}, "bad_field", "name"),
            ({"cmd": "remove_cloud", "name": "missing"}, "not_found", "missing"),
            ({"cmd": "set_view", "view": "front", "width": 16384, "height": 16384}, "limit",
             "pixels"),
            ({"cmd": "hash", "extra": 1}, "bad_field", "extra"),
            ({"cmd": "restore", "name": "../etc"}, "bad_field", "name"),
        ]
        for request, code, words in cases:
            with self.subTest(request=request):
                error = c.error(request)
                self.assertEqual(error["code"], code)
                self.assertIn(words, error["message"])
        for raw in [b"{not json\n", b"[1,2]\n", b"\"text\"\n", b"[" * 100 + b"]" * 100 + b"\n"]:
            c.sock.sendall(raw)
            header, _ = c.read()
            self.assertFalse(header["ok"])
            self.assertEqual(header["error"]["code"], "bad_json")
        # An oversized line is answered once and skipped; the connection stays usable.
        c.sock.sendall(b'{"cmd":"hash","pad":"' + b"x" * 100000 + b'"}\n')
        header, _ = c.read()
        self.assertEqual(header["error"]["code"], "too_large")
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before)
        view = c.ok({"cmd": "get_view", "view": "front"})
        self.assertEqual((view["vfov"], view["width"]), (40.0, 64))

    def test_views_the_platform_cannot_hold_are_refused_before_any_work(self):
        # Within the configured 256 MiP, and as 8-bit within what llvmpipe holds, but as float
        # (EXR) more than its 2 GiB per buffer: refused with `limit` at render and subscribe
        # (it killed the daemon before), and the daemon keeps serving. set_view asks for the
        # view's own format (raw here) and accepts it.
        d = self.daemon(socket_keys="max_image_pixels = 256")
        c = d.client()
        before = c.ok({"cmd": "hash"})
        c.ok({"cmd": "set_view", "view": "front", "width": 11585, "height": 11585})
        for request in [{"cmd": "render", "view": "front", "format": "exr"},
                        {"cmd": "subscribe", "view": "front", "format": "exr", "rate": 1}]:
            with self.subTest(request=request):
                error = c.error(request)
                self.assertEqual(error["code"], "limit")
                self.assertIn("cannot allocate", error["message"])
        c.ok({"cmd": "set_view", "view": "front", "width": 64, "height": 48})
        header, image = c.request({"cmd": "render", "view": "front", "format": "raw"})
        self.assertTrue(header["ok"])
        self.assertEqual(len(image), 64 * 48 * 4)
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before["hash"])
        self.assertIsNone(d.proc.poll())

    def test_hello_and_stats_are_answered_while_the_world_renders(self):
        # Issue 31: hello and stats come from what the world thread published, not from the
        # world thread, so a long render (16 clouds of 4,096 ellipsoids in front of the camera,
        # seconds even at 64x48) does not hold them; stats says what the world has in hand.
        d = self.daemon()
        c = d.client()
        for i in range(16):
            c.ok({"cmd": "add_cloud", "cloud": {"name": f"big{i}", "cumulus": {
                "base": [0, 0, 1000], "width": 3000, "count": 4096}}})
        other = d.client()
        wait_until(lambda: other.ok({"cmd": "stats"})["in_hand"] is None, "the world idle")
        render = c.send({"cmd": "render", "view": "front"})
        wait_until(lambda: (other.ok({"cmd": "stats"})["in_hand"] or {}).get("what") == "render",
                   "the render in hand")
        started = time.monotonic()
        hello = other.ok({"cmd": "hello"})
        waited = time.monotonic() - started
        self.assertEqual(hello["views"], ["front", "left"])
        in_hand = other.ok({"cmd": "stats"})["in_hand"]
        self.assertEqual(in_hand["what"], "render", "the render ended before hello came back")
        self.assertGreaterEqual(in_hand["seconds"], 0.0)
        self.assertLess(waited, 1.0)
        frames = other.ok({"cmd": "stats"})["frames"]
        header, body = c.read()
        self.assertEqual(header["id"], render)
        self.assertTrue(header["ok"], header)
        # Published before the reply went: the client's next stats sees its render.
        self.assertEqual(c.ok({"cmd": "stats"})["frames"], frames + 1)
        for view in ("left", "front"):  # encoded on the encoder thread, and raw
            c.ok({"cmd": "set_view", "view": "front", "width": 32, "height": 24})
            c.request({"cmd": "render", "view": view})
            self.assertEqual(c.ok({"cmd": "stats"})["frames"], frames + 2, view)
            frames += 1

    def test_weather_clouds_tick_and_hash(self):
        d = self.daemon()
        c = d.client()
        h0 = c.ok({"cmd": "hash"})
        stratus = c.ok({"cmd": "set_weather", "layer": 1, "type": 10, "base": 800,
                        "thickness": 300, "coverage": 80})
        self.assertEqual(stratus["layers"], 2)  # a stratus sheet is a base and a top plane
        scud = c.ok({"cmd": "set_weather", "layer": 1, "type": 10, "base": 800,
                     "thickness": 300, "coverage": 80, "scud": 30})
        self.assertEqual(scud["layers"], 3)  # and scud, a plane under the base
        c.ok({"cmd": "set_weather", "layer": 1, "type": 10, "base": 800, "thickness": 300,
              "coverage": 80})
        cumulus = c.ok({"cmd": "set_weather", "layer": 2, "type": 7, "base": 1200,
                        "thickness": 900, "coverage": 10, "wind": [8, 2]})
        self.assertEqual((cumulus["fields"], cumulus["layers"]), (1, 2))  # heaps, no deck
        # One message: a 300 km cluster field on one side of a front, the deck on the other.
        front = {"centre": [0, 0], "size": [300000, 300000], "heading": 45, "transition": 20000}
        h_before = c.ok({"cmd": "hash"})["hash"]
        self.assertEqual(c.error(dict(front, cmd="set_weather", layer=3, type=8,
                                      variation=0.5))["code"], "bad_field")
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], h_before)  # refused: nothing changed
        c.ok(dict(front, cmd="set_weather", layer=1, type=8, coverage=90, front="right"))
        c.ok(dict(front, cmd="set_weather", layer=3, type=7, coverage=40, front="left",
                  spacing=25000, variation=0.6))
        c.ok({"cmd": "set_weather", "layer": 3, "type": 0})
        c.ok({"cmd": "set_weather", "layer": 1, "type": 0})  # none removes the layer
        self.assertEqual(c.ok({"cmd": "set_weather", "layer": 3, "type": 5})["layers"], 0 + 1)
        c.ok({"cmd": "add_cloud", "cloud": {"name": "extra",
                                             "cumulus": {"base": [0, 0, 900], "width": 500}}})
        c.ok({"cmd": "change_cloud", "name": "extra", "move": [10, 0, 0], "threshold": 0.3})
        self.assertEqual(c.error({"cmd": "add_cloud", "cloud": {
            "name": "extra", "cumulus": {}}})["code"], "bad_field")
        c.ok({"cmd": "set_sun", "azimuth": 90, "elevation": 20})
        t = c.ok({"cmd": "tick", "dt": 0.5})
        self.assertAlmostEqual(t["time"], 0.5)
        self.assertEqual(t["ticks"], 1)
        h1 = c.ok({"cmd": "hash"})
        self.assertNotEqual(h0["hash"], h1["hash"])
        self.assertEqual(h1["time_ns"], 500000000)
        c.ok({"cmd": "remove_cloud", "name": "extra"})

    def test_token(self):
        d = self.daemon(name="token", socket_keys='token = "s3cret"')
        c = d.client()
        self.assertEqual(c.error({"cmd": "hash"})["code"], "unauthorized")
        self.assertEqual(c.error({"cmd": "hello", "token": "wrong"})["code"], "unauthorized")
        self.assertEqual(c.error({"cmd": "hash"})["code"], "unauthorized")
        c.ok({"cmd": "hello", "token": "s3cret"})
        c.ok({"cmd": "hash"})

    def test_subscriptions(self):
        d = self.daemon(mode="realtime")
        c = d.client()
        sub = c.ok({"cmd": "subscribe", "view": "front", "rate": 20})
        frames = []
        while len(frames) < 3:
            header, body = c.read()
            if header.get("event") == "frame":
                self.assertEqual(header["subscription"], sub["subscription"])
                self.assertEqual(len(body), 64 * 48 * 4)
                frames.append(header["image"]["frame"])
        self.assertEqual(frames, sorted(frames))
        sent = c.send({"cmd": "unsubscribe", "subscription": sub["subscription"]})
        while True:  # frames already on their way may come first
            header, _ = c.read()
            if header.get("id") == sent:
                self.assertTrue(header["ok"])
                break
        self.assertEqual(c.error({"cmd": "unsubscribe", "subscription": 999})["code"],
                         "not_found")

    def test_twenty_concurrent_clients(self):
        d = self.daemon(mode="realtime")
        failures = []

        def work(i):
            try:
                c = d.client()
                c.ok({"cmd": "hello"})
                for _ in range(3):
                    _, body = c.ok({"cmd": "render", "view": "left" if i % 2 else "front"})
                    assert body[:4] == b"\x89PNG" if i % 2 else len(body) == 64 * 48 * 4
                c.ok({"cmd": "stats"})
                c.close()
            except Exception as e:  # reported below
                failures.append(repr(e))

        threads = [threading.Thread(target=work, args=(i,)) for i in range(20)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(TIMEOUT)
        self.assertEqual(failures, [])
        stats = d.client().ok({"cmd": "stats"})
        self.assertGreaterEqual(stats["frames"], 60)
        # What the last frame did: passes by kind, never more than it counts in all.
        frame = stats["last_frame"]
        self.assertGreater(frame["passes"], 0)
        self.assertEqual(frame["passes"], sum(frame[k] for k in (
            "sky_passes", "ellipsoid_passes", "atlas_passes", "automaton_passes",
            "target_passes", "veil_passes")))
        self.assertLessEqual(frame["layer_terms"], frame["layer_terms_total"])
        self.assertIn("relights", stats)

    def test_full_queue_answers_busy(self):
        d = self.daemon()
        # Five clients pipeline 60 requests each in one write. One connection has at most 16
        # waiting (its reading pauses there), but five overflow the daemon's queue (64):
        # every request is answered, some "busy".
        clients = [d.client() for _ in range(5)]
        sent = {}
        for k, c in enumerate(clients):
            sent[c] = list(range(1000 * (k + 1), 1000 * (k + 1) + 60))
            c.sock.sendall(b"".join((json.dumps({"id": i, "cmd": "render", "view": "front"})
                                     + "\n").encode() for i in sent[c]))
        busy = 0
        for c in clients:
            answered = set()
            while len(answered) < len(sent[c]):
                header, _ = c.read()
                answered.add(header["id"])
                if not header["ok"]:
                    self.assertEqual(header["error"]["code"], "busy")
                    busy += 1
            self.assertEqual(answered, set(sent[c]))
        self.assertGreater(busy, 0)
        clients[0].ok({"cmd": "hash"})  # and the connections still work

    def test_slow_and_vanished_clients_do_not_stall_others(self):
        d = self.daemon(mode="realtime", view_size=(320, 240))
        # A subscriber that never reads, a half-written request, an abrupt disconnect.
        slow = d.client()
        slow.ok({"cmd": "subscribe", "view": "front", "rate": 60})
        half = d.client()
        half.sock.sendall(b'{"cmd":"ha')
        gone = d.client()
        gone.send({"cmd": "render", "view": "front"})
        gone.sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        gone.sock.close()  # reset, with the reply still to come
        c = d.client()
        t0 = c.ok({"cmd": "stats"})
        wait_until(lambda: c.ok({"cmd": "stats"})["frames_dropped"] > 0,
                   "frames to be dropped for the slow subscriber")
        t1 = c.ok({"cmd": "stats"})
        self.assertGreater(t1["ticks"], t0["ticks"])  # time kept moving
        _, body = c.ok({"cmd": "render", "view": "front"})
        self.assertEqual(len(body), 320 * 240 * 4)
        # The half-written request completes later and is answered.
        half.sock.sendall(b'sh"}\n')
        self.assertTrue(half.read()[0]["ok"])

    def test_metrics_endpoint(self):
        d = self.daemon()
        d.client().ok({"cmd": "render", "view": "front"})

        def scrape_with_the_render():
            s = socket.create_connection(("127.0.0.1", d.metrics_port), timeout=TIMEOUT)
            s.sendall(b"GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n")
            text = b""
            while chunk := s.recv(65536):
                text += chunk
            s.close()
            return text if b"nephele_render_seconds_count 1" in text else None
        # The metrics are the figures the world thread last published (once per loop, at
        # least twice a second): wait for the render to be among them.
        text = wait_until(scrape_with_the_render, "the render in the published metrics")
        self.assertIn(b"200 OK", text)
        self.assertIn(b"nephele_ticks_total", text)
        # Latencies are histograms in seconds: cumulative buckets up to +Inf equal the count.
        lines = text.decode().splitlines()
        self.assertIn("# TYPE nephele_render_seconds histogram", lines)
        count = [l for l in lines if l.startswith("nephele_render_seconds_count ")][0]
        inf = [l for l in lines if l.startswith('nephele_render_seconds_bucket{le="+Inf"}')][0]
        self.assertEqual(inf.split()[-1], count.split()[-1])
        self.assertGreater(int(count.split()[-1]), 0)


class LockstepAndSnapshotTest(DaemonTest):
    def drive(self, c):
        c.ok({"cmd": "set_weather", "layer": 1, "type": 9, "base": 900, "coverage": 60,
              "wind": [6, -1]})
        c.ok({"cmd": "add_cloud", "cloud": {"name": "a", "cumulus": {"base": [200, 0, 1000]}}})
        for dt in [0.1, 0.25, 1.0 / 30, 2.0]:
            c.ok({"cmd": "tick", "dt": dt})
        c.ok({"cmd": "set_sun", "azimuth": 120})

    def test_two_daemons_in_lockstep_agree(self):
        a, b = self.daemon(name="a"), self.daemon(name="b")
        ca, cb = a.client(), b.client()
        self.assertEqual(ca.ok({"cmd": "hash"}), cb.ok({"cmd": "hash"}))
        self.drive(ca)
        self.drive(cb)
        ha, hb = ca.ok({"cmd": "hash"}), cb.ok({"cmd": "hash"})
        self.assertEqual(ha, hb)
        self.assertAlmostEqual(ha["time"], 2.38333333, places=6)
        self.assertEqual(ca.ok({"cmd": "render", "view": "front"})[1],
                         cb.ok({"cmd": "render", "view": "front"})[1])
        cb.ok({"cmd": "tick", "dt": 0.1})
        self.assertNotEqual(ca.ok({"cmd": "hash"})["hash"], cb.ok({"cmd": "hash"})["hash"])

    def test_the_world_budget_refuses_what_would_exceed_it(self):
        # Issue 31, item 2: add_cloud past [world] max_ellipsoids is refused with `limit`,
        # naming the budget and the setting, and nothing changes; below it clouds are added.
        d = self.daemon(name="w", world_keys="max_ellipsoids = 5000")
        c = d.client()
        added = c.ok({"cmd": "add_cloud", "cloud": {"name": "a", "cumulus": {
            "base": [0, 0, 1000], "width": 3000, "count": 4096}}})
        self.assertEqual(added["ellipsoids"], 4096)  # with the scene's 27: 4,123 held
        before = c.ok({"cmd": "hash"})["hash"]
        error = c.error({"cmd": "add_cloud", "cloud": {"name": "b", "cumulus": {
            "base": [0, 0, 1000], "count": 1000}}})
        self.assertEqual(error["code"], "limit", error)
        self.assertIn("max_ellipsoids", error["message"])
        self.assertIn("4123", error["message"])
        self.assertIn("5000", error["message"])
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before)
        c.ok({"cmd": "add_cloud", "cloud": {"name": "b", "cumulus": {
            "base": [0, 0, 1000], "count": 877}}})  # exactly the budget
        self.assertEqual(c.error({"cmd": "add_cloud", "cloud": {"name": "c", "cumulus": {
            "base": [0, 0, 1000], "count": 1}}})["code"], "limit")

    def test_sigterm_cancels_the_render_in_hand(self):
        # Issue 31, item 4: SIGTERM during a long render (50 clouds of 4,096 ellipsoids in front
        # of the camera; 25 took 26 s at 64x48 when the issue was filed) cancels it at its next
        # band or batch: its client is answered "shutting down", the snapshot is saved, and the
        # daemon exits 0 within 5 s.
        # The work budget would bound this render (ellipsoid_budget, ellipsoid_overdraw): the
        # scene turns it off.
        scene = os.path.join(self.tmp.name, "unbudgeted.toml")
        with open(SCENE) as f, open(scene, "w") as out:
            out.write(f.read() + "\n[render]\nellipsoid_budget = 0\nellipsoid_overdraw = 0\n")
        d = self.daemon(name="t", extra='[snapshot]\npath = "{snapshot}"\ninterval = 0',
                        scene=scene)
        c = d.client()
        for i in range(50):
            c.ok({"cmd": "add_cloud", "cloud": {"name": f"big{i}", "cumulus": {
                "base": [0, 0, 1000], "width": 3000, "count": 4096}}})
        before = c.ok({"cmd": "hash"})["hash"]
        other = d.client()
        render = c.send({"cmd": "render", "view": "front"})
        wait_until(lambda: (other.ok({"cmd": "stats"})["in_hand"] or {}).get("what") == "render",
                   "the render in hand")
        # A render that makes progress is not a stuck world thread: it beats the heart
        # (/healthz, the systemd watchdog) at each point where it could be cancelled. So while
        # it is in hand some beat must land a second or more after it began; without beats the
        # heart would be at least as old as the render. (The beats are 0.1 to 1.6 s apart here
        # under ThreadSanitizer: one sample at a fixed time could fall in a gap.)
        samples = []
        beat_during_render = False
        deadline = time.monotonic() + 8.0
        while not beat_during_render and time.monotonic() < deadline:
            time.sleep(0.1)
            stats = other.ok({"cmd": "stats"})
            self.assertEqual((stats["in_hand"] or {}).get("what"), "render",
                             "the render ended before SIGTERM: make the world heavier")
            render_age, heart_age = stats["in_hand"]["seconds"], stats["heartbeat_age"]
            samples.append((round(render_age, 2), round(heart_age, 2)))
            beat_during_render = render_age - heart_age > 1.0
        self.assertTrue(beat_during_render, f"(render age, heartbeat age): {samples}")
        started = time.monotonic()
        d.proc.send_signal(signal.SIGTERM)
        code = d.proc.wait(60)
        took = time.monotonic() - started
        self.assertEqual(code, 0, d.log_text()[-2000:])
        # Within 5 s of the signal besides the shutdown snapshot's own writing (1.4 s for these
        # 200,000 ellipsoids under ThreadSanitizer, 0.1 s in a release build).
        saved = re.search(r"event=snapshot reason=shutdown .* ms=([0-9.]+)", d.log_text())
        self.assertIsNotNone(saved, d.log_text()[-2000:])
        self.assertLess(took - float(saved.group(1)) / 1000.0, 5.0, d.log_text()[-2000:])
        header, _ = c.read()
        self.assertEqual(header["id"], render)
        self.assertFalse(header["ok"], header)
        self.assertIn("shutting down", header["error"]["message"])
        d.stop()
        d.start()  # the snapshot holds the world as it was before the render
        self.assertEqual(d.client().ok({"cmd": "hash"})["hash"], before)

    def test_sigterm_saves_and_restart_restores(self):
        d = self.daemon(name="r", extra='[snapshot]\npath = "{snapshot}"\ninterval = 0')
        c = d.client()
        self.drive(c)
        before = c.ok({"cmd": "hash"})
        _, frame = c.ok({"cmd": "render", "view": "front"})
        self.assertEqual(d.stop(), 0)
        self.assertIn("event=snapshot reason=shutdown", d.log_text())
        d.start()
        c = d.client()
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before["hash"])
        self.assertEqual(c.ok({"cmd": "render", "view": "front"})[1], frame)
        # Named snapshots: save, change, restore.
        c.ok({"cmd": "snapshot", "name": "keep"})
        c.ok({"cmd": "tick", "dt": 1.0})
        self.assertNotEqual(c.ok({"cmd": "hash"})["hash"], before["hash"])
        self.assertEqual(c.ok({"cmd": "restore", "name": "keep"})["hash"], before["hash"])
        self.assertEqual(c.error({"cmd": "restore", "name": "nothing"})["code"], "not_found")
        # Issue 12, case 1: a name whose file is a directory, a FIFO or a sparse gigabyte is
        # refused with a message; the daemon keeps answering and the world is unchanged.
        snap_dir = os.path.dirname(d.snapshot)
        os.makedirs(os.path.join(snap_dir, "dir.snap"))
        os.mkfifo(os.path.join(snap_dir, "fifo.snap"))
        with open(os.path.join(snap_dir, "sparse.snap"), "wb") as f:
            f.truncate(1 << 30)
        for name, words in [("dir", "not a regular file"), ("fifo", "not a regular file"),
                            ("sparse", "not a Nephele snapshot")]:
            with self.subTest(name=name):
                error = c.error({"cmd": "restore", "name": name})
                self.assertEqual(error["code"], "failed")
                self.assertIn(words, error["message"])
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before["hash"])

    def test_case62_a_recentring_past_the_range_is_refused_and_the_state_restarts(self):
        """Issue 62: a view at y = 99,990,000 (legal), then set_site 46/7 and 45/7: the second
        would carry the view to y = 100,101,136, beyond what set_view, configs and snapshots
        accept. It is refused with bad_field and changes nothing, and the state snapshots,
        restores and survives a restart. The same holds for a target."""
        d = self.daemon(name="e", extra='[snapshot]\npath = "{snapshot}"\ninterval = 0')
        c = d.client()
        c.ok({"cmd": "set_view", "view": "front", "position": [0, 99990000, 100]})
        c.ok({"cmd": "set_site", "latitude": 46, "longitude": 7})
        before = (c.ok({"cmd": "hash"})["hash"], c.ok({"cmd": "get_view", "view": "front"}),
                  c.ok({"cmd": "set_site"}))
        error = c.error({"cmd": "set_site", "latitude": 45, "longitude": 7})
        self.assertEqual(error["code"], "bad_field", error)
        self.assertIn("view front", error["message"])
        self.assertIn("nothing changed", error["message"])
        self.assertEqual((c.ok({"cmd": "hash"})["hash"],
                          c.ok({"cmd": "get_view", "view": "front"}),
                          c.ok({"cmd": "set_site"})), before)
        # A target at the edge likewise (the view moved back inside first).
        c.ok({"cmd": "set_view", "view": "front", "position": [0, 0, 100]})
        c.ok({"cmd": "add_target", "target": {"name": "buoy", "shape": "box",
                                              "centre": [0, 99990000, 0], "size": [2, 2, 2]}})
        hash_before = c.ok({"cmd": "hash"})["hash"]
        error = c.error({"cmd": "set_site", "latitude": 45, "longitude": 7})
        self.assertEqual(error["code"], "bad_field", error)
        self.assertIn("target buoy", error["message"])
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], hash_before)
        # Northwards everything moves inward: accepted, saved, restored and restarted.
        moved = c.ok({"cmd": "set_site", "latitude": 47, "longitude": 7})
        self.assertTrue(moved["placed"])
        saved = c.ok({"cmd": "snapshot", "name": "edge"})
        self.assertEqual(c.ok({"cmd": "restore", "name": "edge"})["hash"], saved["hash"])
        view = c.ok({"cmd": "get_view", "view": "front"})
        self.assertEqual(d.stop(), 0)
        d.start()
        c = d.client()
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], saved["hash"])
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"}), view)

    def test_case62_a_snapshot_that_does_not_read_at_start_exits_or_starts_fresh(self):
        """Issue 62: a shutdown snapshot that does not read stops the next start, naming the
        file and the field, unless [snapshot] on_error = "start_fresh": then the daemon moves
        it aside (PATH.rejected), logs and counts it, and starts from the scene."""
        extra = '[snapshot]\npath = "{snapshot}"\ninterval = 0\n'
        d = self.daemon(name="bad", extra=extra)
        fresh = d.client().ok({"cmd": "hash"})["hash"]
        self.assertEqual(d.stop(), 0)
        side = d.snapshot + ".daemon.json"
        with open(side) as f:
            state = json.load(f)
        state["requests"][0]["position"] = [0, 100101136, 100]  # as the old daemon wrote it
        with open(side, "w") as f:
            json.dump(state, f)
        with self.assertRaises(AssertionError) as refused:
            d.start()
        self.assertIn(side, str(refused.exception))
        self.assertIn("position", str(refused.exception))
        self.assertIn("start_fresh", str(refused.exception))
        d.stop()
        with open(d.config, "a") as f:
            f.write('on_error = "start_fresh"\n')  # the [snapshot] table is the config's last
        d.start()
        c = d.client()
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], fresh)
        self.assertEqual(c.ok({"cmd": "stats"})["snapshot_failures"], 1)
        self.assertIn("event=snapshot_rejected", d.log_text())
        self.assertTrue(os.path.exists(side + ".rejected"))
        self.assertTrue(os.path.exists(d.snapshot + ".rejected"))
        self.assertFalse(os.path.exists(d.snapshot))

    def test_a_scene_may_start_later_than_one_advance_reaches(self):
        # A scene's time may be up to 1e9 s; one World advance is at most 1e7 s. The daemon
        # gets there in pieces instead of refusing to start.
        scene = os.path.join(self.tmp.name, "late_scene.toml")
        with open(SCENE) as f:
            text = f.read()
        with open(scene, "w") as f:
            f.write("time = 2.5e7\n" + text)
        d = self.daemon(name="late", scene=scene)
        self.assertAlmostEqual(d.client().ok({"cmd": "hash"})["time"], 2.5e7, delta=1e-3)

    def test_kill_9_loses_only_ticks_after_the_last_periodic_snapshot(self):
        d = self.daemon(name="k", extra='[snapshot]\npath = "{snapshot}"\ninterval = 0.1')
        c = d.client()
        self.drive(c)
        saved = c.ok({"cmd": "hash"})
        wait_until(lambda: "reason=periodic path={} time={:.3f} hash={}".format(
            d.snapshot, saved["time"], saved["hash"]) in d.log_text(),
            "a periodic snapshot of the driven world")
        self.assertEqual(d.stop(signal.SIGKILL), -signal.SIGKILL)
        d.start()
        self.assertEqual(d.client().ok({"cmd": "hash"})["hash"], saved["hash"])


class HostStateTest(DaemonTest):
    """Issue 16, items 2 to 5: frames bound to their pose and tick, targets and atmosphere at
    run time, the clock's mode, and snapshots that keep everything the host set."""

    def test_render_of_several_views_and_a_camera_for_one_render(self):
        d = self.daemon()
        c = d.client()
        c.ok({"cmd": "tick", "dt": 0.5})
        sent = c.send({"cmd": "render", "views": ["front", "left"], "format": "raw"})
        parts = [c.read() for _ in range(2)]
        for i, (header, body) in enumerate(parts):
            self.assertEqual(header["id"], sent)
            image = header["result"]["image"]
            self.assertEqual((image["part"], image["parts"]), (i, 2))
            self.assertEqual(image["tick"], 1)
            self.assertEqual(len(body), image["bytes"])
        self.assertEqual([p[0]["result"]["image"]["view"] for p in parts], ["front", "left"])
        self.assertEqual(parts[1][0]["result"]["image"]["camera"]["heading_deg"], -60.0)
        # A camera for this render alone: the header carries it, the view keeps its own.
        camera = {"position": [100, -50, 1200], "heading": 30, "pitch": 5, "roll": 2,
                  "vfov": 40, "width": 80, "height": 40}
        image, body = c.ok({"cmd": "render", "view": "front", "camera": camera, "format": "raw"})
        cam = image["image"]["camera"]
        self.assertEqual(cam["position"], [100, -50, 1200])
        self.assertEqual((cam["heading_deg"], cam["pitch_deg"], cam["roll_deg"]), (30, 5, 2))
        self.assertEqual((image["image"]["width"], image["image"]["height"]), (80, 40))
        self.assertAlmostEqual(cam["focal_px"], 20 / math.tan(math.radians(20)), places=6)
        self.assertEqual(len(body), 80 * 40 * 4)
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["width"], 64)
        for bad, field in [({"views": ["front", "front"]}, "views"),
                           ({"views": ["front", "nope"]}, "view"),
                           ({"views": ["front", "left"], "camera": {"vfov": 30}}, "camera"),
                           ({"view": "front", "camera": {"format": "png"}}, "camera.format"),
                           ({"view": "front", "camera": {"width": 5000, "height": 5000}},
                            "width")]:
            with self.subTest(bad=bad):
                self.assertIn(field, c.error(dict({"cmd": "render"}, **bad))["message"])

    def test_off_axis_view_is_the_centred_view_cropped(self):
        # An asymmetric frustum (CIGI View Definition, set_view "frustum") is drawn as the
        # centred view of the same focal length holding it, cropped: compare with a render of
        # that centred view, cropped here.
        d = self.daemon()
        c = d.client()
        fr = {"left": -20.0, "right": 40.0, "bottom": -10.0, "top": 25.0}
        view = c.ok({"cmd": "set_view", "view": "front", "frustum": fr, "heading": 10})
        t = {k: math.tan(math.radians(v)) for k, v in fr.items()}
        f = 48 / (t["top"] - t["bottom"])
        self.assertEqual(view["frustum"], fr)
        self.assertAlmostEqual(view["vfov"], 35.0)
        half_w = math.ceil(f * max(abs(t["left"]), abs(t["right"])) - 1e-9)
        half_h = math.ceil(f * max(abs(t["bottom"]), abs(t["top"])) - 1e-9)
        x0, x1 = round(half_w + f * t["left"]), round(half_w + f * t["right"])
        y0 = round(half_h - f * t["top"])
        self.assertEqual((view["width"], view["height"]), (x1 - x0, 48))
        image, body = c.ok({"cmd": "render", "view": "front", "format": "raw"})
        cam = image["image"]["camera"]
        self.assertAlmostEqual(cam["focal_px"], f, places=6)
        self.assertEqual(cam["principal_point"], [half_w - x0, half_h - y0])
        centred, full = c.ok({"cmd": "render", "view": "front", "format": "raw", "camera": {
            "vfov": 2 * math.degrees(math.atan(half_h / f)), "width": 2 * half_w,
            "height": 2 * half_h}})
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["frustum"], fr)
        w = x1 - x0
        cropped = b"".join(full[((y0 + y) * 2 * half_w + x0) * 4:((y0 + y) * 2 * half_w + x1) * 4]
                           for y in range(48))
        self.assertEqual(len(body), w * 48 * 4)
        self.assertEqual(body, cropped)
        self.assertGreater(len(set(body[3::4])), 1)  # a cloud edge in view: not a blank test
        # vfov makes the view centred again; a frustum that needs a view above the size limit
        # is refused.
        self.assertNotIn("frustum", c.ok({"cmd": "set_view", "view": "front", "vfov": 50}))
        self.assertIn("frustum", c.error({"cmd": "set_view", "view": "front", "height": 4000,
                                          "frustum": {"left": -88, "right": 1, "bottom": -1,
                                                      "top": 1}})["message"])

    def test_lockstep_subscription_gets_one_frame_per_tick(self):
        d = self.daemon()
        c = d.client()
        sub = c.ok({"cmd": "subscribe", "view": "front", "rate": 60})["subscription"]
        first, _ = c.read()
        self.assertEqual((first["event"], first["image"]["tick"]), ("frame", 0))
        for _ in range(3):
            c.send({"cmd": "tick", "dt": 0.1})
        ticks, replies = [], 0
        while replies < 3:
            header, _ = c.read()
            if header.get("event") == "frame":
                ticks.append(header["image"]["tick"])
            else:
                replies += 1
        while len(ticks) < 3:
            ticks.append(c.read()[0]["image"]["tick"])
        self.assertEqual(ticks, [1, 2, 3])
        # Nothing more arrives while no tick is made, whatever the rate: the next line after a
        # pause is the reply to the next request.
        time.sleep(0.6)
        self.assertEqual(c.ok({"cmd": "hash"})["ticks"], 3)
        c.ok({"cmd": "unsubscribe", "subscription": sub})

    def test_a_subscription_reuses_its_last_frame_and_a_render_is_exact(self):
        # Issue 46, item 2: a view's subscribed frames are one stream whose heaps reuse the
        # last frame (heap_refresh, default 4), while a render reply is the exact frame; the
        # first frame after a world edit is exact again.
        d = self.daemon()
        c = d.client()
        c.ok({"cmd": "subscribe", "view": "front", "rate": 60, "format": "raw"})
        c.read()  # the subscription's first frame: exact
        self.assertEqual(c.ok({"cmd": "stats"})["last_frame"]["reused_passes"], 0)

        def tick():
            c.send({"cmd": "tick", "dt": 0.1})
            frame = reply = None
            while frame is None or reply is None:
                header, body = c.read()
                if header.get("event") == "frame":
                    frame = body
                else:
                    reply = header
            return frame

        streamed = [tick() for _ in range(3)][-1]
        self.assertGreater(c.ok({"cmd": "stats"})["last_frame"]["reused_passes"], 0)
        _, exact = c.ok({"cmd": "render", "view": "front", "format": "raw"})
        self.assertEqual(c.ok({"cmd": "stats"})["last_frame"]["reused_passes"], 0)
        self.assertEqual(len(exact), len(streamed))
        differences = [abs(a - b) for a, b in zip(streamed, exact)]
        self.assertNotEqual(max(differences), 0, "the streamed frame reused nothing")
        self.assertLess(sum(differences) / len(differences), 1.0)  # mean, of 255
        c.ok({"cmd": "set_weather", "layer": 1, "type": 9, "base": 900, "coverage": 30})
        tick()
        self.assertEqual(c.ok({"cmd": "stats"})["last_frame"]["reused_passes"], 0)

    def test_mode_switch_and_tick_in_realtime(self):
        d = self.daemon(mode="realtime")
        c = d.client()
        self.assertIn("realtime mode", c.error({"cmd": "tick", "dt": 0.1})["message"])
        self.assertEqual(c.ok({"cmd": "set_time", "mode": "lockstep"})["mode"], "lockstep")
        before = c.ok({"cmd": "hash"})
        time.sleep(0.3)  # a lockstep world stands still
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before["hash"])
        self.assertEqual(c.ok({"cmd": "tick", "dt": 0.1})["ticks"], before["ticks"] + 1)
        self.assertEqual(c.ok({"cmd": "stats"})["mode"], "lockstep")
        c.ok({"cmd": "set_time", "mode": "realtime", "time_scale": 2})
        wait_until(lambda: c.ok({"cmd": "hash"})["ticks"] > before["ticks"] + 3,
                   "realtime ticks after the switch")
        self.assertIn("mode", c.error({"cmd": "set_time", "mode": "fast"})["message"])

    def test_targets_at_run_time(self):
        d = self.daemon(extra='[[entity_type]]\nid = 1001\nname = "rib"\nshape = "box"\n'
                              'size = [4, 2, 1]\ncolour = [0.9, 0.4, 0.1]\n')
        c = d.client()
        before = c.ok({"cmd": "hash"})["hash"]
        added = c.ok({"cmd": "add_target", "target": {"name": "boat", "type": "rib",
                                                       "centre": [0, 300, 2]}})
        self.assertEqual((added["shape"], added["size"], added["object_id"]),
                         ("box", [4, 2, 1], 1))
        c.ok({"cmd": "add_target", "target": {"name": "buoy", "shape": "ellipsoid",
                                               "centre": [20, 300, 1], "size": [1, 1, 1]}})
        self.assertNotEqual(c.ok({"cmd": "hash"})["hash"], before)
        moved = c.ok({"cmd": "move_target", "name": "boat", "centre": [5, 310, 2],
                      "heading": 45})
        self.assertEqual((moved["centre"], moved["heading"]), ([5, 310, 2], 45))
        listed = c.ok({"cmd": "list_targets"})["targets"]
        self.assertEqual([t["name"] for t in listed], ["boat", "buoy"])
        for target, words in [({"name": "boat", "shape": "box"}, "is taken"),
                              ({"name": "x", "type": "frigate"}, "rib"),
                              ({"name": "x", "mesh": "/etc/passwd"}, "entity_type"),
                              ({"name": "x", "size": [0, 1, 1]}, "size"),
                              ({"name": "x", "shape": "cone"}, "shape"),
                              ({"shape": "box"}, "name")]:
            with self.subTest(target=target):
                self.assertIn(words, c.error({"cmd": "add_target", "target": target})["message"])
        self.assertEqual(c.error({"cmd": "move_target", "name": "nope"})["code"], "not_found")
        c.ok({"cmd": "remove_target", "name": "buoy"})
        self.assertEqual(len(c.ok({"cmd": "list_targets"})["targets"]), 1)

    def test_fog_and_sun_from_date_and_time(self):
        d = self.daemon(extra="[site]\nlatitude = 51.5\nlongitude = -0.1\n")
        c = d.client()
        before = c.ok({"cmd": "hash"})["hash"]
        fog = c.ok({"cmd": "set_fog", "top": 150, "visibility": 800})
        self.assertEqual((fog["enabled"], fog["top"], fog["visibility"]), (True, 150, 800))
        self.assertNotEqual(c.ok({"cmd": "hash"})["hash"], before)
        self.assertEqual(c.ok({"cmd": "set_fog", "enabled": False}), {"enabled": False})
        self.assertIn("visibility", c.error({"cmd": "set_fog", "visibility": 0})["message"])
        # Distance haze: set, kept where unset, removed; bad values change nothing.
        with_haze = c.ok({"cmd": "set_haze", "visibility": 25000})
        self.assertEqual(with_haze, {"enabled": True, "visibility": 25000, "scale_height": 1200})
        self.assertEqual(c.ok({"cmd": "set_haze", "scale_height": 800})["visibility"], 25000)
        hazy = c.ok({"cmd": "hash"})["hash"]
        self.assertIn("10 to 1e+07", c.error({"cmd": "set_haze", "visibility": 5})["message"])
        self.assertIn("removes the haze",
                      c.error({"cmd": "set_haze", "enabled": False, "visibility": 900})["message"])
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], hazy)
        self.assertEqual(c.ok({"cmd": "set_haze", "enabled": False}), {"enabled": False})
        self.assertNotEqual(c.ok({"cmd": "hash"})["hash"], hazy)
        # Midsummer noon at London: the sun due south at 90 - 51.5 + 23.44 degrees.
        sun = c.ok({"cmd": "set_sun", "utc": "2026-06-21T12:00:00Z"})
        self.assertAlmostEqual(sun["elevation"], 90 - 51.5 + 23.44, delta=0.2)
        self.assertAlmostEqual(sun["azimuth"], 180, delta=2.0)
        night = c.ok({"cmd": "set_sun", "utc": "2026-12-21T01:00:00+01:00"})
        self.assertLess(night["elevation"], -50)
        for utc, words in [("2026-02-29T12:00Z", "day"), ("2026-06-21T12:00", "time zone"),
                           ("2200-01-01T00:00Z", "year")]:
            with self.subTest(utc=utc):
                self.assertIn(words, c.error({"cmd": "set_sun", "utc": utc})["message"])
        self.assertIn("not both", c.error({"cmd": "set_sun", "utc": "2026-06-21T12:00Z",
                                           "azimuth": 3})["message"])

    def test_the_sea_by_request_follows_the_surface_wind(self):
        d = self.daemon()
        c = d.client()
        self.assertEqual(c.ok({"cmd": "set_sea"}), {"enabled": False})  # read back: none
        # Trains removed from no sea make none.
        self.assertEqual(c.ok({"cmd": "set_sea", "waves": [{"id": 1, "enabled": False}]}),
                         {"enabled": False})
        before = c.ok({"cmd": "hash"})["hash"]
        # A first field starts from the defaults, with the world's surface wind (none in
        # cumulus.toml: 5 m/s from the west); a new train from its own.
        sea = c.ok({"cmd": "set_sea", "clarity": 0.9,
                    "waves": [{"id": 4, "height": 2.0, "direction": 90}]})
        self.assertEqual(sea, {"enabled": True, "wind": [5.0, 0.0], "fetch": 0.0,
                               "temperature": 15.0, "clarity": 0.9, "whitecaps": True,
                               "seed": 1,
                               "waves": [{"id": 4, "height": 2.0, "wavelength": 100.0,
                                          "period": 8.0, "direction": 90.0, "phase": 0.0}]})
        self.assertNotEqual(c.ok({"cmd": "hash"})["hash"], before)
        # Unset fields keep their values; trains are kept in order of id.
        sea = c.ok({"cmd": "set_sea", "fetch": 50000, "whitecaps": False,
                    "waves": [{"id": 1, "wavelength": 40}, {"id": 4, "period": 0}]})
        self.assertEqual((sea["clarity"], sea["fetch"], sea["whitecaps"]), (0.9, 50000, False))
        self.assertEqual([(w["id"], w["wavelength"], w["period"]) for w in sea["waves"]],
                         [(1, 40.0, 8.0), (4, 100.0, 0.0)])
        self.assertEqual(c.ok({"cmd": "set_sea"}), sea)
        # The sea's wind is the surface wind: it follows set_wind.
        c.ok({"cmd": "set_wind", "velocity": [-3.0, 4.0]})
        self.assertEqual(c.ok({"cmd": "set_sea"})["wind"], [-3.0, 4.0])
        # Bad input names the field and the range, and changes nothing.
        seaed = c.ok({"cmd": "hash"})["hash"]
        for request, words in [
                ({"temperature": 50}, "temperature: 50 is out of range (allowed: -2 to 40)"),
                ({"waves": [{"id": 2, "height": -1}]}, "waves[0].height: -1 is out of range"),
                ({"waves": [{"id": 300}]}, "waves[0].id: 300 is out of range (allowed: 0 to 255)"),
                ({"enabled": False, "fetch": 3}, "false removes the sea"),
                ({"waves": [{"id": i} for i in range(10, 17)]},
                 "waves: the sea would hold 9 wave trains (allowed: at most 8")]:
            with self.subTest(request=request):
                error = c.error(dict(request, cmd="set_sea"))
                self.assertEqual(error["code"], "bad_field")
                self.assertIn(words, error["message"])
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], seaed)
        self.assertEqual(c.ok({"cmd": "set_sea"}), dict(sea, wind=[-3.0, 4.0]))
        # A train removed, then the sea.
        sea = c.ok({"cmd": "set_sea", "waves": [{"id": 1, "enabled": False}]})
        self.assertEqual([w["id"] for w in sea["waves"]], [4])
        self.assertEqual(c.ok({"cmd": "set_sea", "enabled": False}), {"enabled": False})
        self.assertEqual(c.ok({"cmd": "set_sea", "enabled": True})["waves"], [])

    def test_systemd_readiness_watchdog_and_health(self):
        # Item 7: Type=notify readiness through sd_notify, watchdog beats, /healthz.
        path = os.path.join(self.tmp.name, "notify.sock")
        notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        notify.bind(path)
        notify.settimeout(TIMEOUT)
        d = self.daemon(env={"NOTIFY_SOCKET": path, "WATCHDOG_USEC": "400000"})
        messages = []
        while not any(m.startswith("READY=1") for m in messages):
            messages.append(notify.recv(4096).decode())
        self.assertIn(f"socket {d.port}", [m for m in messages if m.startswith("READY=1")][0])
        self.assertEqual(notify.recv(4096).decode(), "WATCHDOG=1")
        with socket.create_connection(("127.0.0.1", d.metrics_port), timeout=TIMEOUT) as h:
            h.sendall(b"GET /healthz HTTP/1.0\r\n\r\n")
            self.assertTrue(h.makefile("rb").readline().startswith(b"HTTP/1.1 200"))
        self.assertEqual(d.stop(), 0)
        rest = []
        notify.settimeout(1)
        try:
            while True:
                rest.append(notify.recv(4096).decode())
        except socket.timeout:
            pass
        self.assertIn("STOPPING=1", rest)
        notify.close()

    def test_restart_restores_everything_the_host_set(self):
        d = self.daemon(name="s", extra='[snapshot]\npath = "{snapshot}"\ninterval = 0')
        c = d.client()
        c.ok({"cmd": "set_view", "view": "left", "position": [10, 20, 800], "heading": 12,
              "vfov": 35, "width": 48, "height": 30, "format": "jpeg", "channels": ["colour"]})
        c.ok({"cmd": "set_weather", "layer": 2, "type": 2, "base": 3000, "thickness": 400,
              "coverage": 70})
        c.ok({"cmd": "set_fog", "top": 90, "visibility": 1500})
        c.ok({"cmd": "add_target", "target": {"name": "t1", "centre": [0, 200, 50]}})
        c.ok({"cmd": "set_sun", "utc": "2026-03-20T09:30:00Z"})
        for _ in range(3):
            c.ok({"cmd": "tick", "dt": 0.2})
        c.ok({"cmd": "render", "view": "front"})
        c.ok({"cmd": "set_time", "time_scale": 3, "paused": True})
        c.ok({"cmd": "set_sea", "temperature": 8, "waves": [{"id": 2, "height": 3}]})
        state = {k: c.ok({"cmd": k}) for k in ["hash", "get_view", "list_targets", "set_sea"]}
        stats = c.ok({"cmd": "stats"})
        self.assertEqual(d.stop(), 0)
        d.start()
        c = d.client()
        for k in ["hash", "get_view", "list_targets", "set_sea"]:
            self.assertEqual(c.ok({"cmd": k}), state[k], k)
        after = c.ok({"cmd": "stats"})
        for k in ["ticks", "frames", "time_scale", "paused", "mode"]:
            self.assertEqual(after[k], stats[k], k)
        # The weather registers (Modbus holding 32 + 8 per layer) came back with the layer.
        from pymodbus.client import ModbusTcpClient
        mb = ModbusTcpClient("127.0.0.1", port=d.modbus_port)
        mb.connect()
        try:
            regs = mb.read_holding_registers(40, 1, slave=1).registers
        finally:
            mb.close()
        self.assertEqual(regs, [2])  # altostratus, in layer 2's type register
        with open(d.snapshot + ".daemon.json") as f:
            self.assertEqual(json.load(f)["ticks"], 3)

    def test_prewarm_leaves_a_weather_change_nothing_to_compile(self):
        """Issue 63, item 6: with [world] prewarm (the default) the world thread compiles every
        shader program a genus asks for after ready, between requests (event=prewarm when done),
        so the first frames after weather changes compile none (stats
        last_frame.programs_compiled); without it they compile some, which is what the count is
        there to tell. The daemon answers while it prewarms."""
        if TIME_FACTOR != 1:
            self.skipTest("a sanitizer build's prewarm takes minutes; the release run checks it")
        compiled = {}
        for prewarm in ("true", "false"):
            d = self.daemon(world_keys=f"prewarm = {prewarm}", name="prewarm-" + prewarm)
            c = d.client()
            c.ok({"cmd": "render", "view": "front", "format": "raw"})
            if prewarm == "true":
                wait_until(lambda: "event=prewarm " in open(d.log_path).read(),
                           "the prewarm's end", timeout=300)
            compiled[prewarm] = 0
            for genus, base, thickness in ((7, 1200, 1500), (10, 500, 400), (1, 3000, 600)):
                c.ok({"cmd": "set_weather", "layer": 1, "type": genus, "base": base,
                      "thickness": thickness, "coverage": 60})
                for view in ("front", "left"):
                    c.ok({"cmd": "render", "view": view, "format": "raw"})
                    compiled[prewarm] += c.ok({"cmd": "stats"})["last_frame"][
                        "programs_compiled"]
            d.stop()
        self.assertEqual(compiled["true"], 0, compiled)
        self.assertGreater(compiled["false"], 0, compiled)


class ModbusTest(DaemonTest):
    def setUp(self):
        super().setUp()
        from pymodbus.client import ModbusTcpClient
        self.d = self.daemon()
        self.mb = ModbusTcpClient("127.0.0.1", port=self.d.modbus_port, timeout=10)
        self.assertTrue(self.mb.connect())
        self.c = self.d.client()

    def tearDown(self):
        self.mb.close()
        super().tearDown()

    def test_registers_follow_the_view_and_writes_steer_it(self):
        regs = self.mb.read_holding_registers(0, 56, slave=1).registers
        self.assertEqual(regs[14:16], [64, 48])
        z = struct.unpack(">f", struct.pack(">HH", *regs[4:6]))[0]
        self.assertAlmostEqual(z, self.c.ok({"cmd": "get_view", "view": "front"})["position"][2])
        self.assertFalse(self.mb.write_registers(6, floats(45.0) + floats(5.0), slave=1).isError())
        view = self.c.ok({"cmd": "get_view", "view": "front"})
        self.assertEqual((view["heading"], view["pitch"]), (45.0, 5.0))
        self.c.ok({"cmd": "set_view", "view": "front", "vfov": 33.0})
        regs = self.mb.read_holding_registers(12, 2, slave=1).registers
        self.assertAlmostEqual(struct.unpack(">f", struct.pack(">HH", *regs))[0], 33.0, 5)
        # Weather layer 1: cumulus at 1500 m, 25 % cover.
        before = self.c.ok({"cmd": "hash"})["hash"]
        self.assertFalse(self.mb.write_registers(
            32, [7] + floats(1500.0) + floats(700.0) + floats(25.0), slave=1).isError())
        self.assertNotEqual(self.c.ok({"cmd": "hash"})["hash"], before)
        regs = self.mb.read_holding_registers(32, 7, slave=1).registers
        self.assertEqual(regs[0], 7)

    def test_fog_and_sun_date_registers(self):
        def unfloat(words):
            return struct.unpack(">f", struct.pack(">HH", *words))[0]
        before = self.c.ok({"cmd": "hash"})["hash"]
        self.assertFalse(self.mb.write_registers(56, floats(120.0) + floats(900.0),
                                                 slave=1).isError())
        self.assertNotEqual(self.c.ok({"cmd": "hash"})["hash"], before)
        date = 20260621
        self.assertFalse(self.mb.write_registers(60, [date >> 16, date & 0xffff] +
                                                 floats(43200.0), slave=1).isError())
        regs = self.mb.read_holding_registers(0, 70, slave=1).registers
        self.assertEqual((unfloat(regs[56:58]), unfloat(regs[58:60])), (120.0, 900.0))
        self.assertAlmostEqual(unfloat(regs[64:66]), 0.75, places=6)  # the default fog colour
        # The colour alone sets the fog whole: same top and visibility, new colour.
        fog_hash = self.c.ok({"cmd": "hash"})["hash"]
        self.assertFalse(self.mb.write_registers(64, floats(0.5) + floats(0.4) + floats(0.3),
                                                 slave=1).isError())
        fog = self.mb.read_holding_registers(56, 14, slave=1).registers
        self.assertEqual([unfloat(fog[i:i + 2]) for i in (0, 2, 8, 10, 12)],
                         [120.0, 900.0, 0.5, 0.4000000059604645, 0.30000001192092896])
        self.assertNotEqual(self.c.ok({"cmd": "hash"})["hash"], fog_hash)
        self.assertTrue(self.mb.write_registers(64, floats(-1.0), slave=1).isError())
        self.assertEqual((regs[60] << 16 | regs[61], unfloat(regs[62:64])), (date, 43200.0))
        # Noon at the default site (0 N, 0 E) at the June solstice: the sun stands to the
        # north at 90 - 23.44 degrees, and the angle registers say so.
        self.assertAlmostEqual(unfloat(regs[22:24]), 90 - 23.44, delta=0.3)
        self.assertLess(min(unfloat(regs[20:22]), 360 - unfloat(regs[20:22])), 5)
        # A day that does not exist is refused and changes nothing; visibility 0 removes fog.
        bad = 20260230
        self.assertTrue(self.mb.write_registers(60, [bad >> 16, bad & 0xffff] + floats(0.0),
                                                slave=1).isError())
        self.assertEqual(self.mb.read_holding_registers(60, 2, slave=1).registers,
                         [date >> 16, date & 0xffff])
        self.assertFalse(self.mb.write_registers(58, floats(0.0), slave=1).isError())
        self.assertEqual(self.mb.read_holding_registers(56, 4, slave=1).registers, [0, 0, 0, 0])
        # The haze (registers 26-29), set whole and read back over the socket and Modbus.
        self.assertFalse(self.mb.write_registers(26, floats(25000.0) + floats(900.0),
                                                 slave=1).isError())
        self.assertEqual(self.c.ok({"cmd": "set_haze"}),
                         {"enabled": True, "visibility": 25000.0, "scale_height": 900.0})
        self.assertEqual(self.mb.read_holding_registers(26, 4, slave=1).registers,
                         floats(25000.0) + floats(900.0))
        self.assertFalse(self.mb.write_registers(26, floats(0.0), slave=1).isError())
        self.assertEqual(self.mb.read_holding_registers(26, 2, slave=1).registers, [0, 0])

    def test_bad_writes_get_exceptions_and_change_nothing(self):
        before = self.c.ok({"cmd": "hash"})["hash"]
        view = self.c.ok({"cmd": "get_view", "view": "front"})
        nan = [0x7FC0, 0x0000]
        cases = [
            (6, nan, 3),                       # NaN heading: ILLEGAL_DATA_VALUE
            (12, floats(500.0), 3),            # vfov out of range
            (14, [0], 3),                      # width 0
            (32, [11], 3),                     # cloud type 11
            (7, [0x4200], 2),                  # half of the heading float: ILLEGAL_DATA_ADDRESS
            (6, [0x4200, 0, 0x4200], 2),       # a float and a half
            (30, [1], 2),                      # reserved register
            (26, floats(5.0), 3),              # haze visibility under 10 m
            (200, [1], 2),                     # outside the map
            (0, floats(1.0) + floats(2.0) + floats(-5.0), 3),  # below the ground
        ]
        for address, values, code in cases:
            with self.subTest(address=address, values=values):
                r = self.mb.write_registers(address, values, slave=1)
                self.assertTrue(r.isError())
                self.assertEqual(r.exception_code, code)
        self.assertEqual(self.c.ok({"cmd": "hash"})["hash"], before)
        self.assertEqual(self.c.ok({"cmd": "get_view", "view": "front"}), view)
        status = self.mb.read_input_registers(0, 12, slave=1).registers
        self.assertEqual(status[9], 1 + 1)  # last error: bad field
        r = self.mb.write_coil(5, True, slave=1)
        self.assertTrue(r.isError())
        self.assertEqual(r.exception_code, 2)

    def test_render_coil_writes_a_file_and_pushes_to_subscribers(self):
        sub = self.c.ok({"cmd": "subscribe", "view": "front", "rate": 0.01})
        first, _ = self.c.read()  # a new subscription is due at once
        self.assertEqual(first["event"], "frame")
        frames_before = self.mb.read_input_registers(1, 2, slave=1).registers
        self.assertFalse(self.mb.write_coil(0, True, slave=1).isError())
        header, body = self.c.read()
        self.assertEqual((header["event"], header["subscription"]), ("frame", sub["subscription"]))
        out = os.path.join(self.tmp.name, "d-frames")
        files = wait_until(lambda: [f for f in os.listdir(out) if f.endswith(".png")]
                           if os.path.isdir(out) else None, "the triggered image")
        with open(os.path.join(out, files[0]), "rb") as f:
            w, h, channels, _ = decode_png(f.read())
        self.assertEqual((w, h, channels), (64, 48, 3))
        wait_until(lambda: not self.mb.read_coils(0, 1, slave=1).bits[0], "the coil to clear")
        frames_after = self.mb.read_input_registers(1, 2, slave=1).registers
        self.assertGreater(frames_after, frames_before)
        # Pause coil: simulation time stands still, and the status register says so.
        self.assertFalse(self.mb.write_coil(1, True, slave=1).isError())
        self.assertEqual(self.mb.read_input_registers(0, 1, slave=1).registers[0], 3)  # lockstep

    def test_mbpoll_reads_and_writes(self):
        out = subprocess.run(["mbpoll", "-m", "tcp", "-a", "1", "-p", str(self.d.modbus_port),
                              "-t", "4", "-0", "-r", "14", "-c", "2", "-1", "127.0.0.1"],
                             capture_output=True, text=True, timeout=TIMEOUT)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("[14]: \t64", out.stdout)
        self.assertIn("[15]: \t48", out.stdout)
        out = subprocess.run(["mbpoll", "-m", "tcp", "-a", "1", "-p", str(self.d.modbus_port),
                              "-t", "4", "-0", "-r", "14", "-1", "127.0.0.1", "80"],
                             capture_output=True, text=True, timeout=TIMEOUT)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(self.c.ok({"cmd": "get_view", "view": "front"})["width"], 80)
        out = subprocess.run(["mbpoll", "-m", "tcp", "-a", "1", "-p", str(self.d.modbus_port),
                              "-t", "4", "-0", "-r", "14", "-1", "127.0.0.1", "0"],
                             capture_output=True, text=True, timeout=TIMEOUT)
        self.assertNotEqual(out.returncode, 0)
        self.assertEqual(self.c.ok({"cmd": "get_view", "view": "front"})["width"], 80)

    def test_allow_list_refuses_other_addresses(self):
        d = self.daemon(name="deny", modbus_keys='allow = ["10.9.8.7"]')
        from pymodbus.client import ModbusTcpClient
        mb = ModbusTcpClient("127.0.0.1", port=d.modbus_port, timeout=2, retries=0)
        mb.connect()
        try:
            refused = mb.read_holding_registers(0, 1, slave=1).isError()
        except Exception:  # pymodbus raises when the server closes the connection
            refused = True
        self.assertTrue(refused)
        mb.close()
        wait_until(lambda: "event=modbus_refused" in d.log_text(), "the refusal in the log")


def rss_mib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise AssertionError("no VmRSS")


def closed_by_peer(sock, timeout=TIMEOUT):
    """True once the daemon has closed `sock` (reads drain any last reply first)."""
    sock.settimeout(timeout)
    try:
        while sock.recv(65536):
            pass
        return True
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False


def mbap(transaction, pdu, protocol=0, length=None, unit=1):
    """A Modbus TCP frame, built byte by byte from the Messaging on TCP/IP guide."""
    n = len(pdu) + 1 if length is None else length
    return struct.pack(">HHHB", transaction, protocol, n, unit) + pdu


def modbus_reply(sock):
    """(transaction, function, data) of one reply frame read from `sock`."""
    def exactly(n):
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise ConnectionError("closed")
            data += chunk
        return data
    transaction, protocol, length, unit = struct.unpack(">HHHB", exactly(7))
    pdu = exactly(length - 1)
    return transaction, pdu[0], pdu[1:]


class AbuseTest(DaemonTest):
    """The abuse cases of docs/RELIABILITY.md, each named by its number there."""

    def test_case04_half_lines_drips_and_idle_clients_never_starve_a_working_one(self):
        d = self.daemon(socket_keys="max_clients = 4\nrequest_timeout = 0.5\nidle_timeout = 0",
                        modbus_keys="max_clients = 2\nrequest_timeout = 0.5\nidle_timeout = 0")
        # Socket: four connections hold half a request line each; the request timeout
        # closes them and a new client is served.
        holders = [socket.create_connection(("127.0.0.1", d.port)) for _ in range(4)]
        for h in holders:
            h.sendall(b'{"cmd": "he')
        for h in holders:
            self.assertTrue(closed_by_peer(h, 10))
        c = d.client()
        c.ok({"cmd": "hello"})
        # A connection dripping a byte every 0.2 s is closed although bytes keep coming.
        drip = socket.create_connection(("127.0.0.1", d.port))
        closed = False
        for b in b'{"cmd": "hello", "id": 1}':
            try:
                drip.sendall(bytes([b]))
            except OSError:
                closed = True
                break
            time.sleep(0.2)
        self.assertTrue(closed or closed_by_peer(drip, 10))
        # Idle connections at the limit: a newcomer takes the place of the idlest.
        idle = [d.client() for _ in range(3)]
        time.sleep(0.6)  # longer than the request timeout: they count as idle
        newcomer = d.client()
        newcomer.ok({"cmd": "hello"})
        self.assertTrue(any(closed_by_peer(i.sock, 0.5) for i in [c] + idle))
        self.assertIn("reason=evicted_idle", d.log_text())
        # Modbus: two idle clients at the limit, a third is served; a dripping one is closed.
        idle_mb = [socket.create_connection(("127.0.0.1", d.modbus_port)) for _ in range(2)]
        time.sleep(0.6)
        mb = socket.create_connection(("127.0.0.1", d.modbus_port), timeout=TIMEOUT)
        mb.sendall(mbap(7, struct.pack(">BHH", 3, 14, 2)))
        self.assertEqual(modbus_reply(mb), (7, 3, struct.pack(">BHH", 4, 64, 48)))
        drip = socket.create_connection(("127.0.0.1", d.modbus_port))
        try:
            for b in mbap(8, struct.pack(">BHH", 3, 14, 2))[:6]:
                drip.sendall(bytes([b]))
                time.sleep(0.2)
        except OSError:
            pass  # closed while dripping
        self.assertTrue(closed_by_peer(drip, 10))
        mb.sendall(mbap(9, struct.pack(">BHH", 3, 14, 1)))
        self.assertEqual(modbus_reply(mb)[0], 9)
        for s in idle_mb + [mb, drip]:
            s.close()
        # Metrics: a scrape that never finishes its request is closed by the same timeout.
        m = socket.create_connection(("127.0.0.1", d.metrics_port))
        m.sendall(b"GET /metr")
        self.assertTrue(closed_by_peer(m, 10))
        m.close()

    def test_case05_unread_image_replies_stay_within_the_pending_limit(self):
        # Under AddressSanitizer freed memory waits in a quarantine and would count as growth.
        asan = os.environ.get("ASAN_OPTIONS")
        env = {"ASAN_OPTIONS": asan + ":quarantine_size_mb=0"} if asan else None
        d = self.daemon(socket_keys="max_pending_mb = 1", view_size=(512, 512), env=env)
        c = d.client()
        c.ok({"cmd": "render", "view": "front"})  # 1 MiB, and the renderer is warm
        before = rss_mib(d.proc.pid)
        ids = [c.send({"cmd": "render", "view": "front"}) for _ in range(40)]
        watcher = d.client()
        # Wait until the daemon has done what it will with the 40 without their being read.
        last = -10
        while True:
            stats = watcher.ok({"cmd": "stats"})  # itself one request
            if stats["requests"] == last + 1 and stats["queue"]["depth"] == 0:
                break
            last = stats["requests"]
            time.sleep(0.3)
        grown = rss_mib(d.proc.pid) - before
        self.assertLess(grown, 12, f"the daemon grew by {grown:.0f} MiB for one unread client")
        answered, images, busy = set(), 0, 0
        while len(answered) < len(ids):
            header, body = c.read()
            answered.add(header["id"])
            if header["ok"]:
                self.assertEqual(len(body), 512 * 512 * 4)
                images += 1
            else:
                self.assertEqual(header["error"]["code"], "busy")
                busy += 1
        self.assertEqual(answered, set(ids))
        self.assertGreater(images, 0)

    def test_case06_subscriptions_end_with_their_client_and_resets_are_counted(self):
        d = self.daemon(socket_keys="max_subscriptions = 2", view_size=(512, 512))
        watcher = d.client()
        for _ in range(2):
            c = d.client()
            c.ok({"cmd": "subscribe", "view": "front", "rate": 0.01})  # one frame per 100 s
            c.read()  # the first frame
            c.close()
        wait_until(lambda: watcher.ok({"cmd": "stats"})["subscriptions"] == 0,
                   "the vanished clients' subscriptions to end", timeout=5)
        subscriber = d.client()  # the limit is free again
        self.assertIn("subscription", subscriber.ok(
            {"cmd": "subscribe", "view": "front", "rate": 0.01}))
        # Thirty clients reset in the middle of a 1 MiB image.
        for _ in range(30):
            c = Client(d.port)
            c.send({"cmd": "render", "view": "front"})
            c.file.readline()
            c.sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            c.close()
        wait_until(lambda: watcher.ok({"cmd": "stats"})["clients"]["socket"] == 2,
                   "the client count to come back to two", timeout=10)

    def test_case07_a_client_over_the_limit_is_refused_with_its_request_id(self):
        d = self.daemon(socket_keys="max_clients = 2")
        held = [d.client() for _ in range(2)]
        for c in held:
            c.ok({"cmd": "hello"})  # busy, so not idle
        extra = Client(d.port)
        error = extra.error({"cmd": "hello", "id": "refused-7"})
        self.assertEqual(error["code"], "limit")
        self.assertTrue(closed_by_peer(extra.sock, 5))
        extra.close()

    def test_case08_wrong_tokens_close_the_connection(self):
        d = self.daemon(socket_keys='token = "s3cret-token"')
        c = d.client()
        for i in range(3):
            self.assertEqual(c.error({"cmd": "hello", "token": "guess%d" % i})["code"],
                             "unauthorized")
        self.assertTrue(closed_by_peer(c.sock, 5))
        ok = d.client()
        ok.ok({"cmd": "hello", "token": "s3cret-token"})
        ok.ok({"cmd": "hash"})

    def test_case09_a_modbus_write_refused_busy_changes_nothing(self):
        from pymodbus.client import ModbusTcpClient
        d = self.daemon(modbus_keys="request_timeout = 0.2", view_size=(2048, 2048))
        c = d.client()
        heading = c.ok({"cmd": "get_view", "view": "front"})["heading"]
        mb = ModbusTcpClient("127.0.0.1", port=d.modbus_port, timeout=10, retries=0)
        self.assertTrue(mb.connect())
        # Twelve 16 MiB renders keep the world thread busy for seconds.
        c.sock.sendall(b"".join(
            (json.dumps({"id": i, "cmd": "render", "view": "front", "channels": ["colour"]})
             + "\n").encode() for i in range(12)))
        c.read()  # the first is done, so the other eleven are queued ahead of the write
        r = mb.write_registers(6, floats(123.0), slave=1)
        self.assertTrue(r.isError())
        self.assertEqual(r.exception_code, 6)
        for _ in range(11):
            c.read()
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["heading"], heading)
        # An accepted write is answered once applied.
        self.assertFalse(mb.write_registers(6, floats(77.0), slave=1).isError())
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["heading"], 77.0)
        mb.close()

    def test_case10_modbus_frames_are_framed_strictly_by_the_mbap_header(self):
        d = self.daemon()
        c = d.client()
        view = c.ok({"cmd": "get_view", "view": "front"})

        def connect():
            return socket.create_connection(("127.0.0.1", d.modbus_port), timeout=TIMEOUT)
        s = connect()
        # A read whose length also covers a hidden write frame: refused, nothing written.
        hidden = mbap(2, struct.pack(">BHHB", 16, 6, 2, 4) + struct.pack(">f", 99.0))
        s.sendall(mbap(1, struct.pack(">BHH", 3, 0, 2) + hidden))
        self.assertEqual(modbus_reply(s), (1, 0x83, bytes([3])))
        # Trailing bytes inside the length: refused.
        s.sendall(mbap(3, struct.pack(">BHH", 3, 0, 2) + b"\0"))
        self.assertEqual(modbus_reply(s), (3, 0x83, bytes([3])))
        # Function codes this server does not serve, 0x80 and above included: exception 1,
        # and the stream stays in step.
        for transaction, function in ((4, 0x83), (5, 0x07), (6, 0x2B), (7, 0x80)):
            s.sendall(mbap(transaction, bytes([function])))
            self.assertEqual(modbus_reply(s), (transaction, function | 0x80, bytes([1])))
        s.sendall(mbap(8, struct.pack(">BHH", 3, 14, 2)))
        self.assertEqual(modbus_reply(s), (8, 3, struct.pack(">BHH", 4, 64, 48)))
        # A protocol id other than 0, and lengths that cannot be framed: the connection closes.
        for frame in (mbap(9, struct.pack(">BHH", 3, 0, 1), protocol=0x1234),
                      mbap(10, b"", length=1), mbap(11, b"", length=300)):
            t = connect()
            t.sendall(frame)
            self.assertTrue(closed_by_peer(t, 5))
            t.close()
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"}), view)
        s.close()

    def test_case11_sigterm_finishes_promised_replies_and_answers_queued_ones(self):
        # With 1 MiB of unread output allowed, the daemon stops reading this client once the
        # image is out, so some of its requests are still unread at SIGTERM.
        d = self.daemon(view_size=(2048, 2048), socket_keys="max_pending_mb = 1",
                        extra="[snapshot]\npath = \"{snapshot}\"\ninterval = 0\n")
        c = Client(d.port, receive_buffer=65536)  # so the image cannot hide in the kernel
        d.clients.append(c)
        c.sock.sendall(b"".join(json.dumps(r).encode() + b"\n" for r in
                                [{"id": 0, "cmd": "render", "view": "front"}] +
                                [{"id": i, "cmd": "render", "view": "left"}
                                 for i in range(1, 40)]))
        first, rest = 0, list(range(1, 40))
        watcher = d.client()
        wait_until(lambda: watcher.ok({"cmd": "stats"})["frames"] >= 1, "the render")
        d.proc.send_signal(signal.SIGTERM)
        # Read nothing until the world thread has stopped: the unread requests must then be
        # answered by the connection itself, after the whole image.
        wait_until(lambda: "event=snapshot reason=shutdown" in d.log_text(), "the stop")
        header, body = c.read()
        self.assertEqual(header["id"], first)
        self.assertEqual(len(body), 2048 * 2048 * 4)
        answered = {}
        for _ in rest:
            header, _ = c.read()
            answered[header["id"]] = header
        self.assertEqual(set(answered), set(rest))
        for h in answered.values():
            self.assertTrue(h["ok"] or h["error"]["code"] in ("busy", "failed"), h)
        self.assertTrue(any(not h["ok"] and "shutting down" in h["error"]["message"]
                            for h in answered.values()))
        self.assertEqual(d.stop(), 0)
        # A shutdown snapshot that cannot be written makes the exit code say so.
        d.start()
        snapshot_dir = os.path.dirname(d.snapshot)
        for name in os.listdir(snapshot_dir):
            os.remove(os.path.join(snapshot_dir, name))
        os.rmdir(snapshot_dir)
        open(snapshot_dir, "w").close()  # a file where the directory should be
        self.assertEqual(d.stop(), 1)
        self.assertIn("event=snapshot_failed", d.log_text())


    def test_case12_a_full_disk_fails_the_write_not_the_daemon(self):
        from pymodbus.client import ModbusTcpClient
        full = tempfile.mkdtemp(prefix="nephele-full-")
        self.addCleanup(os.rmdir, full)
        if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", full],
                          capture_output=True).returncode != 0:
            self.skipTest("cannot mount a small tmpfs here (the render command test injects "
                          "the failure with a file-size limit instead)")
        self.addCleanup(subprocess.run, ["umount", "-l", full])
        frames = os.path.join(full, "frames")
        # Keys after [output]'s directory stay in that table.
        d = self.daemon(view_size=(512, 384), frames=frames, extra='format = "jpeg"')
        os.mkdir(frames)
        filler = os.open(os.path.join(full, "filler"), os.O_WRONLY | os.O_CREAT)
        try:  # fill the disk
            while os.write(filler, b"\0" * 4096):
                pass
        except OSError:
            pass
        os.close(filler)
        mb = ModbusTcpClient("127.0.0.1", port=d.modbus_port, timeout=10, retries=0)
        self.assertTrue(mb.connect())
        c = d.client()
        errors = c.ok({"cmd": "stats"})["errors"]
        self.assertFalse(mb.write_coil(0, True, slave=1).isError())
        wait_until(lambda: "event=render_trigger_failed" in d.log_text(), "the failure logged")
        self.assertEqual(os.listdir(frames), [])  # no empty or partial file
        self.assertGreater(c.ok({"cmd": "stats"})["errors"], errors)
        # Room again: the next trigger writes a whole JPEG.
        os.remove(os.path.join(full, "filler"))
        self.assertFalse(mb.write_coil(0, True, slave=1).isError())
        wait_until(lambda: os.listdir(frames), "the image")
        wait_until(lambda: not mb.read_coils(0, 1, slave=1).bits[0], "the coil to clear")
        names = os.listdir(frames)
        self.assertEqual(len(names), 1)
        self.assertTrue(names[0].endswith(".jpg"))
        with open(os.path.join(frames, names[0]), "rb") as f:
            data = f.read()
        self.assertEqual((data[:2], data[-2:]), (b"\xff\xd8", b"\xff\xd9"))  # SOI ... EOI
        mb.close()


    def test_case13_one_name_rule_and_weather_in_its_own_namespace(self):
        d = self.daemon()
        c = d.client()
        before = c.ok({"cmd": "hash"})["hash"]
        cumulus = {"base": [0, 0, 900], "width": 500}
        bad = ["two words", "line\nbreak", "x" * 1000, "h\u00e9llo", "weather/1/heap0",
               ".hidden", "", "a/b"]
        for name in bad:
            with self.subTest(name=name[:20]):
                error = c.error({"cmd": "add_cloud", "cloud": {"name": name, "cumulus": cumulus}})
                self.assertEqual(error["code"], "bad_field")
                self.assertIn("is not a name", error["message"])
                for cmd in ({"cmd": "remove_cloud", "name": name},
                            {"cmd": "get_view", "view": name},
                            {"cmd": "snapshot", "name": name}):
                    self.assertEqual(c.error(cmd)["code"], "bad_field", cmd)
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before)
        # A user's cloud whose name resembles the weather's survives set_weather, and what is
        # added can be removed.
        for name in ("weather1", "weather-1", "weather.1"):
            c.ok({"cmd": "add_cloud", "cloud": {"name": name, "cumulus": cumulus}})
        c.ok({"cmd": "set_weather", "layer": 1, "type": 7, "base": 1200, "thickness": 800,
              "coverage": 30})
        c.ok({"cmd": "set_weather", "layer": 1, "type": 0})
        for name in ("weather1", "weather-1", "weather.1"):
            c.ok({"cmd": "remove_cloud", "name": name})

    def test_case15_a_number_no_double_holds_is_refused_not_fatal(self):
        """2^53 + 1 where a number is read aborted the daemon (std::bad_optional_access) in
        every request read through the scene-file tables: add_target, add_cloud."""
        d = self.daemon()
        c = d.client()
        before = c.ok({"cmd": "hash"})["hash"]
        big = 2**53 + 1
        for request, field in (
                ({"cmd": "add_target", "target": {"name": "t", "shape": "box",
                                                  "centre": [0, 0, big], "size": [1, 1, 1]}},
                 "target.centre"),
                ({"cmd": "add_cloud", "cloud": {"name": "c", "ellipsoid": [
                    {"centre": [0, 0, 1000], "radii": [300, 200, big]}]}},
                 "cloud.ellipsoid[0].radii"),
                ({"cmd": "add_cloud", "cloud": {"name": "c", "threshold": -big,
                                                "cumulus": {"base": [0, 0, 900], "width": 500}}},
                 "cloud.threshold"),
                ({"cmd": "add_cloud", "cloud": {"name": "c", "cumulus": {
                    "base": [0, 0, 900], "width": 2**64}}}, "cloud.cumulus.width"),
                ({"cmd": "move_target", "name": "t", "centre": [big, 0, 0]}, "centre"),
                ({"cmd": "set_view", "view": "front", "heading": big}, "heading")):
            with self.subTest(field=field):
                error = c.error(request)
                self.assertEqual(error["code"], "bad_field", error)
                self.assertTrue(error["message"].startswith(field + ":"), error)
        self.assertIsNone(d.proc.poll(), "the daemon died")
        self.assertEqual(c.ok({"cmd": "hash"})["hash"], before)

    def test_case14_out_of_descriptors_the_daemon_waits_instead_of_spinning(self):
        """With the file-descriptor limit reached, accepting fails while connections wait in
        the backlog; the daemon must pause between attempts (not burn a core) and serve
        newcomers once descriptors are free."""
        import resource
        # Under the sanitizer build UBSan cannot check a vptr while no descriptor is free: on
        # a miss in its type cache the runtime probes whether the vtable is readable by
        # writing it into a pipe (compiler-rt's IsAccessibleMemoryRange), the pipe cannot be
        # made, and a sound object is reported as having an "invalid vptr" whose "memory
        # cannot be printed" (reproduced with a ten-line program that exhausts its
        # descriptors and compares two std::error_code). The runtime's suppressions cannot
        # match it (they match the dynamic type, which the failed probe leaves unknown), so
        # this case lets UBSan go on after a report and accepts exactly that report, at the
        # error_category calls of <system_error>; any other report fails the case.
        ubsan = os.environ.get("UBSAN_OPTIONS")
        env = {"UBSAN_OPTIONS": ubsan + ":halt_on_error=0"} if ubsan else None

        def cpu_seconds(pid):
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

        d = self.daemon(env=env)
        first = d.client()
        first.ok({"cmd": "hello"})
        open_fds = len(os.listdir(f"/proc/{d.proc.pid}/fd"))
        soft, hard = resource.prlimit(d.proc.pid, resource.RLIMIT_NOFILE)
        resource.prlimit(d.proc.pid, resource.RLIMIT_NOFILE, (open_fds + 2, hard))
        waiting = [socket.create_connection(("127.0.0.1", d.port)) for _ in range(6)]
        time.sleep(0.5)  # the free descriptors are taken; the rest wait in the backlog
        before = cpu_seconds(d.proc.pid)
        time.sleep(2.0)
        used = cpu_seconds(d.proc.pid) - before
        self.assertLess(used, 0.5, f"the daemon used {used:.2f} s of CPU in 2 s while out of "
                        "descriptors")
        self.assertIn("accept_failed", d.log_text())
        for s in waiting:
            s.close()
        first.close()
        resource.prlimit(d.proc.pid, resource.RLIMIT_NOFILE, (soft, hard))
        deadline = time.time() + 20
        while True:  # the closed backlog entries are accepted and dropped first
            try:
                d.client().ok({"cmd": "hello"})
                break
            except (OSError, AssertionError):
                if time.time() > deadline:
                    raise
                time.sleep(0.2)
        # Every UBSan report must be that one: a member call on the error_category of
        # <system_error> said to have an invalid vptr (with the object's bytes and a stack
        # when the runtime finds a descriptor for them, "memory cannot be printed" when not).
        lines = d.log_text().splitlines()
        probe_failure = re.compile(r"\S*/system_error:\d+:\d+: runtime error: member call on "
                                   r"address (0x[0-9a-f]+) which does not point to an object "
                                   r"of type 'error_category'$")
        for k, line in enumerate(lines):
            if "runtime error" not in line:
                continue
            match = probe_failure.fullmatch(line)
            self.assertTrue(match, line)
            self.assertEqual(lines[k + 1] if k + 1 < len(lines) else "",
                             match.group(1) + ": note: object has invalid vptr", line)


    def test_live_fuzz_of_every_command_leaves_the_daemon_answering(self):
        """tests/daemon/live_fuzz.py: every command of protocol/commands.inc with the fields
        and ranges its reader names, over three connections, among snapshot files that are a
        directory, a FIFO, a sparse file and junk. One well-formed reply per request, each
        within 5 s; snapshot round trips give back their hash; a restart restores the shutdown
        snapshot. NEPHELE_LIVE_FUZZ sets the seconds (default 20)."""
        import live_fuzz
        seconds = float(os.environ.get("NEPHELE_LIVE_FUZZ", "20"))

        def daemon():
            d = self.daemon(**LIVE_FUZZ_DAEMON)
            snaps = os.path.dirname(d.snapshot)
            os.makedirs(snaps, exist_ok=True)
            os.mkdir(os.path.join(snaps, "dir.snap"))
            os.mkfifo(os.path.join(snaps, "fifo.snap"))
            with open(os.path.join(snaps, "sparse.snap"), "wb") as f:
                f.truncate(1 << 30)
            with open(os.path.join(snaps, "junk.snap"), "wb") as f:
                f.write(b"NEPHSNAP" + bytes(range(256)) * 4)
            return d

        d, figures = live_fuzz.run(daemon, SOURCE, seconds, seed=12)
        print(f"live fuzz: {figures['requests']} requests, {figures['round_trips']} round "
              f"trips, slowest reply {figures['max_reply_s']:.2f} s ({figures['slowest']})")
        self.assertGreater(figures["round_trips"], 0)
        # Snapshots named like the directory and the FIFO fail to be written, and are counted;
        # none may fail to read back what was written.
        self.assertNotIn("does not read back", d.log_text())
        self.assertEqual(d.stop(), 0, d.log_text()[-2000:])

    def test_case18_modbus_clients_that_drop_mid_frame_free_their_slots_at_once(self):
        """Fifty clients connect, send half a frame and drop; a working client right after them
        is served. Their threads may not have read the end of the connection yet (or not even
        started) when the newcomer is accepted, so the closed ones must not count against the
        limit. Twenty rounds at a limit of 1: before the fix about nine rounds in ten were
        refused. The socket listener likewise (there about one round in three)."""
        d = self.daemon(socket_keys="max_clients = 1", modbus_keys="max_clients = 1")
        half_frame = mbap(1, struct.pack(">BHH", 3, 14, 2))[:5]
        for round in range(20):
            dropped = [socket.create_connection(("127.0.0.1", d.modbus_port)) for _ in range(50)]
            for s in dropped:
                s.sendall(half_frame)
            for s in dropped:
                s.close()
            with socket.create_connection(("127.0.0.1", d.modbus_port), timeout=TIMEOUT) as mb:
                mb.sendall(mbap(10 + round, struct.pack(">BHH", 3, 14, 2)))
                try:
                    reply = modbus_reply(mb)
                except ConnectionError:
                    self.fail(f"round {round}: the working Modbus client was refused")
            self.assertEqual(reply, (10 + round, 3, struct.pack(">BHH", 4, 64, 48)))
        for round in range(20):
            dropped = [socket.create_connection(("127.0.0.1", d.port)) for _ in range(50)]
            for s in dropped:
                s.sendall(b'{"cmd": "he')
            for s in dropped:
                s.close()
            c = Client(d.port)
            header, _ = c.request({"cmd": "hello"})
            c.close()
            self.assertTrue(header["ok"], f"round {round}: the working client was refused: "
                            f"{header}")

    def test_case19_a_connection_flood_writes_a_bounded_log(self):
        """Connections refused at the client limit and connections that open and drop, 300 of
        each on the socket and the Modbus listener: the log keeps the first 10 lines of each
        kind and one summary line per 10 s with the count held back (docs/RELIABILITY.md), so
        1200 connections write under 150 lines (measured: 72; before: about 1400), while stats
        count every refusal."""
        import re
        n = 300
        d = self.daemon(socket_keys="max_clients = 2\nrequest_timeout = 60\nidle_timeout = 0",
                        modbus_keys="max_clients = 2\nrequest_timeout = 60\nidle_timeout = 0")
        holders = [d.client() for _ in range(2)]
        for h in holders:
            h.ok({"cmd": "hello"})
        mb_holders = [socket.create_connection(("127.0.0.1", d.modbus_port), timeout=TIMEOUT)
                      for _ in range(2)]
        for i, m in enumerate(mb_holders):
            m.sendall(mbap(i, struct.pack(">BHH", 3, 14, 2)))
            self.assertEqual(modbus_reply(m)[0], i)
        errors_before = holders[0].ok({"cmd": "stats"})["errors"]
        # Refused: working clients hold every slot.
        for port in (d.port, d.modbus_port):
            for _ in range(n):
                socket.create_connection(("127.0.0.1", port)).close()
        wait_until(lambda: holders[0].ok({"cmd": "stats"})["errors"] >= errors_before + 2 * n,
                   "every refusal counted")
        log = d.log_text()
        self.assertLessEqual(log.count("event=client_refused"), 10)
        self.assertLessEqual(log.count("event=modbus_refused"), 10)
        # Accepted and dropped in the middle of a request: one slot free on each listener.
        holders.pop().close()
        mb_holders.pop().close()
        for port, half in ((d.port, b'{"cmd": "he'), (d.modbus_port, mbap(1, b"\x03")[:5])):
            for _ in range(n):
                with socket.create_connection(("127.0.0.1", port)) as s:
                    s.sendall(half)
        # Newcomers queue behind the flood: once they are served, all of it was handled.
        c = d.client()
        c.ok({"cmd": "hello"})
        c.close()
        with socket.create_connection(("127.0.0.1", d.modbus_port), timeout=TIMEOUT) as mb:
            mb.sendall(mbap(7, struct.pack(">BHH", 3, 14, 2)))
            self.assertEqual(modbus_reply(mb)[0], 7)
        mb_holders[0].sendall(mbap(8, struct.pack(">BHH", 3, 14, 2)))
        self.assertEqual(modbus_reply(mb_holders[0])[0], 8)
        refused = holders[0].ok({"cmd": "stats"})["errors"] - errors_before
        self.assertGreaterEqual(refused, 2 * n)
        self.assertEqual(d.stop(), 0)
        log = d.log_text()
        lines = log.splitlines()
        self.assertLess(len(lines), 150, "\n".join(lines[-40:]))
        # At most 10 lines of each kind; closes are of several kinds (eof, shutdown, ...).
        for event in ("client_connected", "client_closed", "modbus_connected", "modbus_closed"):
            self.assertLessEqual(sum(f"event={event} " in line for line in lines), 40, event)
        # Every refusal is in the log: written, or counted in a summary of its kind.
        summarised = sum(int(count) for count in re.findall(
            r"event=log_suppressed kind=(?:client|modbus)_refused/max_clients count=(\d+)", log))
        written = log.count("event=client_refused") + log.count("event=modbus_refused")
        self.assertEqual(written + summarised, refused, "\n".join(lines[-40:]))
        self.assertRegex(log, r"event=log_suppressed kind=modbus_connected count=\d+")


if __name__ == "__main__":
    unittest.main()
