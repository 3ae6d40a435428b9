"""nephele.cigi against a real daemon: a lockstep `nephele serve` with CIGI on, driven by
CigiHost, and what its packets did read back over the socket protocol.

NEPHELE_BINARY and NEPHELE_SOURCE_DIR as for test_daemon.py."""
import unittest
from pathlib import Path

from test_daemon import DaemonTest, write_config

from nephele import cigi

SITE = (51.5, -1.25)  # the config's [site]: the database origin
TICK_RATE = 30  # the config's [world] tick_rate


class CigiHostTest(DaemonTest):
    def config(self) -> Path:
        config = write_config(self.directory.name)
        with open(config, "a") as f:
            f.write(f"[cigi]\nenabled = true\nig_port = 0\nhost_port = 0\n"
                    f"[site]\nlatitude = {SITE[0]}\nlongitude = {SITE[1]}\n")
        return config

    def setUp(self) -> None:
        super().setUp()
        self.host = cigi.CigiHost("127.0.0.1", self.daemon.ports["cigi"], timeout=30.0)

    def tearDown(self) -> None:
        self.host.close()
        super().tearDown()

    def test_the_ownship_carries_the_views_and_each_frame_ticks(self) -> None:
        reply = self.host.frame(cigi.entity_control(0, SITE[0], SITE[1], 500.0, yaw=90.0))
        self.assertEqual((reply.last_host_frame, reply.ig_status, reply.ig_mode),
                         (1, 0, cigi.IgMode.OPERATE))
        view = self.client.get_view(view="front")
        for got, expected in zip(view["position"], [0.0, 0.0, 500.0]):
            self.assertAlmostEqual(got, expected, places=3)
        self.assertAlmostEqual(view["heading"], 90.0, places=4)
        # The first frame of a run ticks one period; the next ones by their timestamps.
        self.assertAlmostEqual(self.client.hash()["time"], 1 / TICK_RATE)
        reply = self.host.frame(dt=0.5)
        self.assertEqual(reply.last_host_frame, 2)
        clock = self.client.hash()
        self.assertEqual(clock["ticks"], 2)
        self.assertAlmostEqual(clock["time"], 1 / TICK_RATE + 0.5)

    def test_atmosphere_and_the_sun(self) -> None:
        reply = self.host.frame(
            cigi.entity_control(0, SITE[0], SITE[1], 300.0),
            cigi.atmosphere_control(visibility=20000.0, wind_speed=8.0, wind_direction=270.0),
            cigi.celestial_sphere_control(2026, 6, 21, 12, 0))
        self.assertEqual(reply.ig_status, 0)
        haze = self.client.set_haze()  # no field: reads the haze back
        self.assertEqual((haze["enabled"], haze["visibility"]), (True, 20000.0))
        sea = self.client.set_sea(enabled=True)  # the sea takes the surface wind
        self.assertAlmostEqual(sea["wind"][0], 8.0, places=4)  # from the west: blowing east
        self.assertAlmostEqual(sea["wind"][1], 0.0, places=4)
        # Noon UT at the June solstice, 51.5 N: the sun stands 90 - 51.5 + 23.44 degrees up.
        sun = self.client.set_sun()
        self.assertAlmostEqual(sun["elevation"], 90.0 - SITE[0] + 23.44, delta=0.5)
        self.assertLess(abs(sun["azimuth"] - 180.0), 5.0)

    def test_a_packet_out_of_range_is_refused_alone(self) -> None:
        before = self.client.get_view(view="front")["position"]
        reply = self.host.frame(cigi.entity_control(0, 95.0, SITE[1], 500.0),
                                cigi.atmosphere_control(visibility=15000.0))
        self.assertEqual(reply.ig_status, 1)
        self.assertEqual(self.client.get_view(view="front")["position"], before)
        self.assertEqual(self.client.set_haze()["visibility"], 15000.0)
        self.assertEqual(self.client.stats()["cigi"]["refused_bad_value"], 1)


if __name__ == "__main__":
    unittest.main()
