"""The installed `nephele` package against a real daemon: `nephele serve` on port 0 in lockstep
mode, started through nephele.LocalDaemon, rendered, subscribed to, steered and refused.

NEPHELE_BINARY names the daemon (default: build/nephele in the repository), NEPHELE_SOURCE_DIR
the repository (default: three folders above this file)."""
import os
import tempfile
import unittest
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

import nephele

SOURCE = Path(os.environ.get("NEPHELE_SOURCE_DIR", Path(__file__).resolve().parents[3]))
BINARY = os.environ.get("NEPHELE_BINARY", str(SOURCE / "build" / "nephele"))
TOKEN = "s3cret"


def write_config(directory: str, socket_keys: str = "") -> Path:
    """A lockstep daemon with the cumulus scene: a raw 64x48 view and a PNG 32x24 one."""
    config = Path(directory) / "daemon.toml"
    config.write_text(f'''scene = "{SOURCE / "config" / "scenes" / "cumulus.toml"}"
[world]
mode = "lockstep"
tick_rate = 30
prewarm = false
[[view]]
name = "front"
width = 64
height = 48
format = "raw"
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
enabled = false
''')
    return config


def srgb8(linear: NDArray[np.float32]) -> NDArray[np.int64]:
    """Linear to 8-bit sRGB, written here from IEC 61966-2-1 as a reference."""
    c = np.clip(linear.astype(np.float64), 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    levels: NDArray[np.int64] = np.round(255.0 * encoded).astype(np.int64)
    return levels


class DaemonTest(unittest.TestCase):
    """One daemon per test, so that every test starts from the scene as loaded."""

    def setUp(self) -> None:
        self.directory = tempfile.TemporaryDirectory()
        self.log = open(Path(self.directory.name) / "daemon.log", "w")
        self.daemon = self.start(self.config())
        self.client = self.daemon.client(timeout=30.0)

    def tearDown(self) -> None:
        self.client.close()
        self.daemon.stop()
        self.log.close()
        self.directory.cleanup()

    def config(self) -> Path:
        return write_config(self.directory.name)

    def start(self, config: Path) -> nephele.LocalDaemon:
        return nephele.LocalDaemon(config, BINARY, stderr=self.log)


class RenderTest(DaemonTest):
    def test_hello_names_the_views(self) -> None:
        hello = self.client.hello()
        self.assertEqual((hello["protocol"], hello["views"], hello["mode"]),
                         (1, ["front", "left"], "lockstep"))

    def test_raw_colour_and_coverage_are_bytes(self) -> None:
        frame = self.client.render("front")
        self.assertEqual(list(frame.channels), ["colour", "coverage"])
        colour, coverage = frame["colour"], frame["coverage"]
        self.assertEqual((colour.dtype, colour.shape), (np.uint8, (48, 64, 3)))
        self.assertEqual((coverage.dtype, coverage.shape), (np.uint8, (48, 64)))
        # The arrays are the wire's RGBA pixels, top row first.
        rgba = np.frombuffer(bytes(frame.data), np.uint8).reshape(48, 64, 4)
        np.testing.assert_array_equal(colour, rgba[:, :, :3])
        np.testing.assert_array_equal(coverage, rgba[:, :, 3])
        self.assertTrue((coverage > 0).any() and (coverage == 0).any())  # a cloud, and sky
        self.assertEqual((frame.view, frame.width, frame.height, frame.tick), ("front", 64, 48, 0))
        view = self.client.get_view(view="front")
        self.assertEqual(list(frame.camera.position), view["position"])
        self.assertAlmostEqual(frame.camera.focal_px, 24 / np.tan(np.radians(view["vfov"] / 2)))

    def test_byte_channels_keep_their_layout_whatever_the_order_asked(self) -> None:
        both = self.client.render("front", channels=["colour", "coverage"])
        reversed_order = self.client.render("front", channels=["coverage", "colour"])
        np.testing.assert_array_equal(reversed_order["colour"], both["colour"])
        np.testing.assert_array_equal(reversed_order["coverage"], both["coverage"])
        colour_only = self.client.render("front", channels=["colour"])
        np.testing.assert_array_equal(colour_only["colour"], both["colour"])

    def test_ground_truth_channels_are_float_planes(self) -> None:
        names = ["visibility", "colour", "depth", "object_id", "coverage", "cloud_depth"]
        planes = self.client.render("front", format="raw", channels=names)
        self.assertEqual(planes.encoding, "float32-planes")
        self.assertEqual(list(planes.channels), names)
        for name in names:
            expected = (48, 64, 3) if name == "colour" else (48, 64)
            self.assertEqual((planes[name].dtype, planes[name].shape), (np.float32, expected))
        np.testing.assert_allclose(planes["visibility"] + planes["coverage"], 1.0, atol=1e-6)
        self.assertTrue(np.isinf(planes["depth"][0]).any())  # sky in the top row
        self.assertTrue((planes["depth"][np.isfinite(planes["depth"])] > 0).all())
        self.assertTrue((planes["object_id"] == 0).all())  # no target in the scene
        # Linear colour is the 8-bit frame's before its sRGB encoding.
        srgb = self.client.render("front", channels=["colour"])["colour"]
        self.assertLessEqual(np.abs(srgb8(planes["colour"]) - srgb).max(), 1)

    def test_several_views_are_of_one_tick(self) -> None:
        front, left = self.client.render(views=["front", "left"])
        self.assertEqual((front.view, front.format, left.view, left.format),
                         ("front", "raw", "left", "png"))
        self.assertEqual(front.tick, left.tick)
        self.assertEqual(left.channels, {})
        self.assertEqual(bytes(left.data[:4]), b"\x89PNG")

    def test_to_pil(self) -> None:
        frame = self.client.render("front")
        image = frame.to_pil()
        self.assertEqual((image.mode, image.size), ("RGB", (64, 48)))
        np.testing.assert_array_equal(np.asarray(image), frame["colour"])
        self.assertEqual(self.client.render("left").to_pil().size, (32, 24))
        depth = self.client.render("front", channels=["depth"]).to_pil("depth")
        self.assertEqual((depth.mode, depth.size), ("L", (64, 48)))
        self.assertEqual((frame._repr_png_() or b"")[:4], b"\x89PNG")  # Jupyter's display


class SteeringTest(DaemonTest):
    def test_set_weather_changes_the_frame(self) -> None:
        before = self.client.render("front")
        result = self.client.set_weather(layer=1, type=10, base=600, thickness=200, coverage=100,
                                         wind=[5, 0])
        self.assertEqual((result["layer"], result["type"]), (1, "stratus"))  # named in replies
        after = self.client.render("front")
        self.assertEqual(after.tick, before.tick)  # the same time: only the weather changed
        self.assertFalse(np.array_equal(after["colour"], before["colour"]))
        self.assertEqual(self.client.set_weather(layer=1, type=0)["type"], "none")

    def test_set_view_and_tick(self) -> None:
        view = self.client.set_view(view="front", heading=30.0, width=40, height=30)
        self.assertEqual((view["heading"], view["width"], view["height"]), (30.0, 40, 30))
        self.assertEqual(self.client.tick(dt=0.5)["ticks"], 1)
        frame = self.client.render("front")
        self.assertEqual((frame.width, frame.tick, frame.camera.heading_deg), (40, 1, 30.0))
        self.assertEqual(frame["colour"].shape, (30, 40, 3))

    def test_numpy_arguments_are_sent_and_nan_is_not(self) -> None:
        with self.assertRaises(ValueError):
            self.client.set_wind(velocity=[float("nan"), 0.0])
        self.assertTrue(self.client.connected)
        self.client.set_wind(velocity=np.array([3.0, 1.0]))
        self.assertEqual(self.client.set_sea(enabled=True)["wind"], [3.0, 1.0])
        view = self.client.set_view(view="front", heading=np.float32(45.0), width=np.int64(32))
        self.assertEqual((view["heading"], view["width"]), (45.0, 32))

    def test_a_refusal_is_an_exception_with_the_daemons_code(self) -> None:
        with self.assertRaises(nephele.NepheleError) as refused:
            self.client.set_view(view="front", pitch=200)
        self.assertEqual(refused.exception.code, "bad_field")
        self.assertIn("pitch", refused.exception.message)
        with self.assertRaises(nephele.NepheleError) as missing:
            self.client.render("nowhere")
        self.assertEqual(missing.exception.code, "not_found")
        self.assertEqual(self.client.hash()["ticks"], 0)  # the connection is still usable


class SubscriptionTest(DaemonTest):
    def test_lockstep_frames_follow_the_ticks(self) -> None:
        subscription = self.client.subscribe("front")
        first = next(subscription)
        self.assertEqual((first.tick, first.subscription), (0, subscription.id))
        ticks = []
        for _ in range(3):
            self.client.tick(dt=0.1)
            frame = next(subscription)
            ticks.append(frame.tick)
            self.assertEqual(frame["colour"].shape, (48, 64, 3))
            self.assertEqual(frame.camera.position, first.camera.position)
        self.assertEqual(ticks, [1, 2, 3])
        subscription.close()
        self.assertFalse(subscription.active)
        self.assertEqual(list(subscription), [])  # the iteration has ended
        with self.assertRaises(nephele.NepheleError) as gone:
            self.client.unsubscribe(subscription.id)
        self.assertEqual(gone.exception.code, "not_found")

    def test_unread_frames_beyond_the_queue_are_dropped_and_counted(self) -> None:
        self.client.queued_frames = 2
        with self.client.subscribe("front", format="raw", channels=["coverage"]) as frames:
            for _ in range(4):
                self.client.tick(dt=0.1)
            received = []
            for frame in frames:
                received.append(frame.tick)
                if frame.tick == 4:
                    break
        self.assertEqual(received, sorted(received))
        self.assertEqual(len(received) + frames.dropped, 5)  # ticks 0 to 4

    def test_a_timeout_closes_the_connection_and_reconnect_opens_one(self) -> None:
        subscription = self.client.subscribe("front")
        next(subscription)
        self.client.timeout = 0.2
        with self.assertRaises(nephele.RequestTimeout):
            next(subscription)  # lockstep: no tick, no frame
        self.assertFalse(self.client.connected or subscription.active)
        with self.assertRaises(ConnectionError):
            self.client.hash()
        self.client.reconnect()
        self.assertEqual(self.client.hash()["ticks"], 0)


class TokenTest(DaemonTest):
    def config(self) -> Path:
        return write_config(self.directory.name, socket_keys=f'token = "{TOKEN}"')

    def test_the_token_is_sent_on_every_connection(self) -> None:
        with self.assertRaises(nephele.NepheleError) as refused:
            self.client.hash()
        self.assertEqual(refused.exception.code, "unauthorized")
        with self.daemon.client(token=TOKEN) as client:
            self.assertEqual(client.hash()["ticks"], 0)
            client.reconnect()
            self.assertEqual(client.hash()["ticks"], 0)

