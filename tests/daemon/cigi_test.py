#!/usr/bin/python3
"""CIGI 3.3 end to end: a host written here from the ICD's packet layouts (not from Nephele's
codec) drives `nephele serve` over loopback UDP. Every datagram either side sends is written
to a capture file and decoded by Wireshark's CIGI dissector (tshark), whose fields must equal
what the host meant and what it read back.

Run by ctest with NEPHELE_BINARY and NEPHELE_SOURCE_DIR set."""
import json
import math
import os
import shutil
import socket
import struct
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from daemon_test import DaemonTest, wait_until  # noqa: E402

ENTITY_TYPE = 1001
SITE = (51.5, -1.25)  # the config's [site]


# ---- The host: packets from the CIGI 3.3 ICD's layouts ----------------------------------

def ig_control(frame, timestamp=None, mode=1, bo=">", version=3, minor=3, database=0):
    flags = mode | ((timestamp is not None) << 2) | (minor << 4)
    return struct.pack(bo + "BBBbBBHIII4x", 1, 24, version, database, flags, 0, 0x8000, frame,
                       timestamp or 0, 0)


def entity_control(entity, lat, lon, alt, yaw=0.0, pitch=0.0, roll=0.0, etype=ENTITY_TYPE,
                   state=1, attached=0, parent=0, bo=">"):
    return struct.pack(bo + "BBHBBBBHHfffddd", 2, 48, entity, state | (attached << 2), 0, 255, 0,
                       etype, parent, roll, pitch, yaw, lat, lon, alt)


def view_control(view, entity, x=0.0, y=0.0, z=0.0, roll=0.0, pitch=0.0, yaw=0.0, bo=">"):
    return struct.pack(bo + "BBHBBHffffff", 16, 32, view, 0, 0x3F, entity, x, y, z, roll, pitch,
                       yaw)


def view_definition(view, left, right, top, bottom, near=1.0, far=50000.0, bo=">"):
    return struct.pack(bo + "BBHBBBBffffff", 21, 32, view, 0, 0x3F, 0, 0, near, far, left, right,
                       top, bottom)


def weather_control(layer, enabled, cloud_type=0, coverage=0.0, base=0.0, thickness=0.0,
                    visibility=0.0, wind=0.0, wind_from=0.0, transition=0.0, scope=0, region=0,
                    scud=None, severity=0, bo=">"):
    """scud: the scud frequency, percent, with scud enabled; None leaves it disabled."""
    return struct.pack(bo + "BBHBBBB" + "f" * 12, 12, 56, region, layer, 50,
                       int(enabled) | (int(scud is not None) << 1) | (cloud_type << 4),
                       scope | (severity << 2),
                       15.0, visibility, scud or 0.0, coverage, base, thickness, transition, wind,
                       0.0, wind_from, 1013.0, 0.0)


def region_control(region, state, lat, lon, size_x, size_y, rotation=0.0, perimeter=0.0,
                   corner=0.0, merge=False, bo=">"):
    """Environmental Region Control (11): state 0 inactive, 1 active, 2 destroyed."""
    return struct.pack(bo + "BBHB3xddfffff4x", 11, 48, region, state | (int(merge) << 2), lat, lon,
                       size_x, size_y, corner, rotation, perimeter)


def atmosphere_control(visibility, wind, wind_from, bo=">"):
    return struct.pack(bo + "BBBBffffff4x", 10, 32, 1, 50, 15.0, visibility, wind, 0.0,
                       wind_from, 1013.0)


def maritime_control(enabled, whitecaps, temperature, clarity, height=0.0, scope=0, region=0,
                     bo=">"):
    """Maritime Surface Conditions Control (13): clarity in percent; scope 0 global, 1
    regional, 2 entity."""
    return struct.pack(bo + "BBHB3xfff4x", 13, 24, region,
                       int(enabled) | (int(whitecaps) << 1) | (scope << 2), height, temperature,
                       clarity)


def wave_control(wave, enabled, height=1.0, wavelength=100.0, period=0.0, direction=0.0,
                 phase=0.0, leading=0.0, breaker=0, scope=0, region=0, bo=">"):
    """Wave Control (14): direction is where the wave propagates, degrees from true north."""
    return struct.pack(bo + "BBHBB2xffffff", 14, 32, region, wave,
                       int(enabled) | (scope << 1) | (breaker << 3), height, wavelength, period,
                       direction, phase, leading)


def celestial_control(month, day, year, hour, minute, bo=">"):
    return struct.pack(bo + "BBBBB3xIf", 9, 16, hour, minute, 0x1F,
                       month * 1000000 + day * 10000 + year, 0.0)


def decode_sof(data):
    """Start of Frame, byte order from its magic number."""
    bo = ">" if data[6:8] == b"\x80\x00" else "<"
    (pid, size, version, database, status, flags, magic, ig_frame, timestamp,
     last_host) = struct.unpack(bo + "BBBbBBHIII4x", data[:24])
    return {"id": pid, "size": size, "version": version, "database": database,
            "status": status, "mode": flags & 3, "minor": flags >> 4, "order": bo, "ig_frame": ig_frame,
            "timestamp": timestamp, "last_host_frame": last_host, "bytes": len(data)}


# ---- Independent references ---------------------------------------------------------------

def enu(lat, lon, alt, lat0, lon0):
    """East, north of a point seen from the origin, through WGS 84 Earth-centred coordinates
    (exact), and its altitude."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)

    def ecef(la, lo, h):
        la, lo = math.radians(la), math.radians(lo)
        n = a / math.sqrt(1 - e2 * math.sin(la) ** 2)
        return ((n + h) * math.cos(la) * math.cos(lo), (n + h) * math.cos(la) * math.sin(lo),
                (n * (1 - e2) + h) * math.sin(la))
    p, o = ecef(lat, lon, 0.0), ecef(lat0, lon0, 0.0)
    d = [p[i] - o[i] for i in range(3)]
    la0, lo0 = math.radians(lat0), math.radians(lon0)
    east = -math.sin(lo0) * d[0] + math.cos(lo0) * d[1]
    north = (-math.sin(la0) * math.cos(lo0) * d[0] - math.sin(la0) * math.sin(lo0) * d[1]
             + math.cos(la0) * d[2])
    return east, north, alt


def database(lat, lon, alt, site):
    """A point in the daemon's database about `site` (its stats' "site": latitude, longitude
    and grid north): east and north about the origin turned by the grid north."""
    east, north, up = enu(lat, lon, alt, site["latitude"], site["longitude"])
    g = math.radians(site["grid"])
    return (east * math.cos(g) - north * math.sin(g), east * math.sin(g) + north * math.cos(g),
            up)


def north_bearing(lat, lon, site):
    """The database bearing of true north at a point: the unit north there, Earth-centred,
    on the origin's east and north turned by the grid north."""
    la, lo = math.radians(lat), math.radians(lon)
    n = (-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la))
    la0, lo0 = math.radians(site["latitude"]), math.radians(site["longitude"])
    e0 = (-math.sin(lo0), math.cos(lo0), 0.0)
    n0 = (-math.sin(la0) * math.cos(lo0), -math.sin(la0) * math.sin(lo0), math.cos(la0))
    east = sum(a * b for a, b in zip(n, e0))
    north = sum(a * b for a, b in zip(n, n0))
    return math.degrees(math.atan2(east, north)) - site["grid"]


def sun_spencer(year, month, day, hour, minute, lat, lon):
    """Sun elevation and azimuth by Spencer's (1971) Fourier series for declination and the
    equation of time: a different method from Nephele's Meeus coordinates, good to ~0.2 deg."""
    doy = time.strptime(f"{year}-{month}-{day}", "%Y-%m-%d").tm_yday
    g = 2 * math.pi / 365 * (doy - 1 + (hour - 12) / 24)
    decl = (0.006918 - 0.399912 * math.cos(g) + 0.070257 * math.sin(g)
            - 0.006758 * math.cos(2 * g) + 0.000907 * math.sin(2 * g)
            - 0.002697 * math.cos(3 * g) + 0.00148 * math.sin(3 * g))
    eqtime = 229.18 * (0.000075 + 0.001868 * math.cos(g) - 0.032077 * math.sin(g)
                       - 0.014615 * math.cos(2 * g) - 0.040849 * math.sin(2 * g))
    ha = math.radians((hour * 60 + minute + eqtime + 4 * lon) / 4 - 180)
    phi = math.radians(lat)
    el = math.asin(math.sin(phi) * math.sin(decl) + math.cos(phi) * math.cos(decl) * math.cos(ha))
    az = math.atan2(math.sin(ha), math.cos(ha) * math.sin(phi) - math.tan(decl) * math.cos(phi))
    return math.degrees(el), (math.degrees(az) + 180) % 360


def dissected_number(value):
    """A number as tshark's JSON gives it: booleans as "1"/"0" or "True"/"False"."""
    return float({"true": 1, "false": 0}.get(str(value).lower(), value))


def unfloat(words):
    return struct.unpack(">f", struct.pack(">HH", *words))[0]


def holding_registers(daemon):
    """The daemon's first 64 Modbus holding registers, read by a fresh client."""
    from pymodbus.client import ModbusTcpClient
    mb = ModbusTcpClient("127.0.0.1", port=daemon.modbus_port)
    mb.connect()
    try:
        return mb.read_holding_registers(0, 64, slave=1).registers
    finally:
        mb.close()


# ---- Capture and dissection -----------------------------------------------------------------

class Capture:
    """The datagrams of a test as a pcap file (Ethernet, IPv4, UDP on 127.0.0.1)."""

    def __init__(self):
        self.records = []

    def add(self, payload, src_port, dst_port):
        udp = struct.pack(">HHHH", src_port, dst_port, 8 + len(payload), 0) + payload
        ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 0, 0, 64, 17, 0,
                         bytes([127, 0, 0, 1]), bytes([127, 0, 0, 1]))
        self.records.append(b"\0" * 12 + b"\x08\x00" + ip + udp)

    def dissect(self, path, ports, fields):
        """tshark's values of `fields` per datagram: a list of {field: [values]}."""
        with open(path, "wb") as f:
            f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
            for i, frame in enumerate(self.records):
                f.write(struct.pack("<IIII", i, 0, len(frame), len(frame)) + frame)
        args = ["tshark", "-r", path, "-T", "json"]
        for p in ports:
            args += ["-d", f"udp.port=={p},cigi"]
        for field in fields:
            args += ["-e", field]
        out = subprocess.run(args, capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        return [p["_source"]["layers"] for p in json.loads(out.stdout)]


class CigiTest(DaemonTest):
    def setUp(self):
        super().setUp()
        if not shutil.which("tshark"):
            self.fail("tshark is missing: run deploy/setup.sh (Debian package tshark)")
        self.host = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.host.bind(("127.0.0.1", 0))
        self.host.settimeout(10)
        self.host_port = self.host.getsockname()[1]
        self.capture = Capture()

    def tearDown(self):
        self.host.close()
        super().tearDown()

    def start(self, mode="lockstep", site=True):
        site_table = f"[site]\nlatitude = {SITE[0]}\nlongitude = {SITE[1]}\n" if site else ""
        d = self.daemon(mode=mode, extra=f'''[cigi]
enabled = true
ig_port = 0
host_port = {self.host_port}
views = ["front", "left"]
{site_table}[[entity_type]]
id = {ENTITY_TYPE}
name = "rib"
shape = "box"
size = [4, 2, 1]
''')
        self.ig_port = d.ports["cigi"]
        self.assertGreater(self.ig_port, 0)
        return d

    def send(self, *packets):
        data = b"".join(packets)
        self.host.sendto(data, ("127.0.0.1", self.ig_port))
        self.capture.add(data, self.host_port, self.ig_port)
        return data

    def receive_sof(self):
        data, _ = self.host.recvfrom(65536)
        self.capture.add(data, self.ig_port, self.host_port)
        return decode_sof(data)

    def frame(self, *packets, frame, timestamp=None, bo=">"):
        self.send(ig_control(frame, timestamp, bo=bo), *packets)
        sof = self.receive_sof()
        self.assertEqual(sof["last_host_frame"], frame)
        return sof

    def no_reply(self, seconds=0.3):
        self.host.settimeout(seconds)
        try:
            with self.assertRaises(socket.timeout):
                self.host.recvfrom(65536)
        finally:
            self.host.settimeout(10)

    def test_a_host_drives_views_entities_clouds_fog_and_sun(self):
        d = self.start()
        c = d.client()
        lat, lon = SITE[0] + 0.01, SITE[1] + 0.02  # about 1.4 km east, 1.1 km north
        boat = (SITE[0] + 0.015, SITE[1] + 0.021, 2.0)
        sof = self.frame(entity_control(0, lat, lon, 1200.0, yaw=30.0, pitch=-5.0),
                         view_definition(0, -30.0, 30.0, 20.0, -20.0),
                         view_control(1, 0, x=2.0, y=0.5, z=-1.0, yaw=-60.0),
                         view_definition(1, -50.0, 10.0, 15.0, -5.0),
                         entity_control(7, *boat, yaw=90.0),
                         weather_control(1, True, 7, coverage=40.0, base=1500.0, thickness=800.0,
                                         wind=10.0, wind_from=270.0),
                         weather_control(0, True, base=0.0, thickness=120.0, visibility=900.0),
                         atmosphere_control(20000.0, 5.0, 90.0),
                         celestial_control(6, 21, 2026, 14, 30), frame=1, timestamp=100000)
        self.assertEqual((sof["id"], sof["size"], sof["version"], sof["minor"], sof["mode"],
                          sof["order"], sof["ig_frame"]), (101, 24, 3, 3, 1, ">", 1))
        front = c.ok({"cmd": "get_view", "view": "front"})
        east, north, up = enu(lat, lon, 1200.0, *SITE)
        self.assertAlmostEqual(front["position"][0], east, delta=1.0)
        self.assertAlmostEqual(front["position"][1], north, delta=1.0)
        self.assertAlmostEqual(front["position"][2], up, delta=1e-6)
        # The host's heading is from true north at the ownship: the database's north there is
        # turned by the meridians' convergence, (lon - lon0) sin(lat), 0.016 degree here.
        site = c.ok({"cmd": "stats"})["site"]
        self.assertEqual((site["latitude"], site["longitude"], site["grid"]), (*SITE, 0.0))
        self.assertAlmostEqual(front["heading"], 30.0 + north_bearing(lat, lon, site), places=4)
        self.assertAlmostEqual(front["pitch"], -5.0, places=4)
        self.assertAlmostEqual(front["vfov"], 40.0, places=4)  # top 20, bottom -20
        self.assertEqual(front["width"],
                         round(48 * math.tan(math.radians(30)) / math.tan(math.radians(20))))
        # View 1 sits 2 m ahead, 0.5 m right and 1 m up on the ownship, looking 60 deg left.
        left = c.ok({"cmd": "get_view", "view": "left"})
        h, p = math.radians(30.0), math.radians(-5.0)
        fwd = (math.sin(h) * math.cos(p), math.cos(h) * math.cos(p), math.sin(p))
        right = (math.cos(h), -math.sin(h), 0.0)
        upv = (-math.sin(h) * math.sin(p), -math.cos(h) * math.sin(p), math.cos(p))
        for i in range(3):
            expected = front["position"][i] + 2.0 * fwd[i] + 0.5 * right[i] + 1.0 * upv[i]
            self.assertAlmostEqual(left["position"][i], expected, delta=1e-3)
        self.assertAlmostEqual(left["heading"], 330.0, delta=0.2)
        # An asymmetric frustum: drawn off-axis, its sides as asked.
        self.assertEqual(left["frustum"], {"left": -50.0, "right": 10.0, "bottom": -5.0,
                                           "top": 15.0})
        self.assertAlmostEqual(left["vfov"], 20.0)
        targets = c.ok({"cmd": "list_targets"})["targets"]
        self.assertEqual([t["name"] for t in targets], ["cigi-7"])
        be, bn, bu = enu(*boat, *SITE)
        self.assertAlmostEqual(targets[0]["centre"][0], be, delta=1.0)
        self.assertAlmostEqual(targets[0]["centre"][1], bn, delta=1.0)
        boat_north = north_bearing(boat[0], boat[1], site)
        self.assertAlmostEqual(targets[0]["heading"], 90.0 + boat_north, places=6)
        self.assertEqual(targets[0]["size"], [4, 2, 1])
        # The weather, fog and sun as the Modbus registers read them.
        regs = holding_registers(d)
        self.assertEqual(regs[32], 7)  # cumulus
        self.assertEqual([unfloat(regs[33:35]), unfloat(regs[35:37]), unfloat(regs[37:39])],
                         [1500.0, 800.0, 40.0])
        self.assertEqual([unfloat(regs[56:58]), unfloat(regs[58:60])], [120.0, 900.0])
        self.assertEqual(regs[60] << 16 | regs[61], 20260621)
        el, az = sun_spencer(2026, 6, 21, 14, 30, *SITE)
        self.assertAlmostEqual(unfloat(regs[22:24]), el, delta=0.3)
        self.assertAlmostEqual(unfloat(regs[20:22]), az, delta=0.5)
        # Atmosphere Control's global visibility is the distance haze (set_haze with no field
        # reads it back unchanged).
        self.assertEqual(c.ok({"cmd": "set_haze"}),
                         {"enabled": True, "visibility": 20000.0, "scale_height": 1200.0})
        # The same packets again change nothing (no regeneration of the layer), and moving
        # the boat moves it; inactive removes it.
        hash_before = c.ok({"cmd": "hash"})
        self.frame(weather_control(1, True, 7, coverage=40.0, base=1500.0, thickness=800.0,
                                   wind=10.0, wind_from=270.0), frame=2, timestamp=101667)
        self.assertEqual(c.ok({"cmd": "list_targets"})["targets"], targets)
        self.assertEqual(c.ok({"cmd": "hash"})["ticks"], hash_before["ticks"] + 1)
        self.frame(entity_control(7, *boat, yaw=95.0), frame=3, timestamp=103334)
        self.assertAlmostEqual(c.ok({"cmd": "list_targets"})["targets"][0]["heading"],
                               95.0 + boat_north, places=6)
        # A target removed over the socket: the next frame that moves it is refused by the
        # world (Start of Frame says so: IG status 4), and the one after places it afresh.
        c.ok({"cmd": "remove_target", "name": "cigi-7"})
        self.send(ig_control(4, 105001), entity_control(7, *boat, yaw=100.0))
        self.assertEqual(self.receive_sof()["status"], 4)
        self.frame(entity_control(7, *boat, yaw=100.0), frame=5, timestamp=106668)
        self.assertAlmostEqual(c.ok({"cmd": "list_targets"})["targets"][0]["heading"],
                               100.0 + boat_north, places=6)
        self.frame(entity_control(7, *boat, state=0), frame=6, timestamp=108335)
        self.assertEqual(c.ok({"cmd": "list_targets"})["targets"], [])
        stats = c.ok({"cmd": "stats"})["cigi"]
        self.assertEqual(stats["messages"], 5)
        self.assertEqual(stats["refused_refused_by_world"], 1)
        self.assertNotIn("refused_malformed", stats)
        self.check_with_tshark()

    def test_the_sun_and_the_database_follow_the_ownship_across_the_earth(self):
        """Issue 29, item 1: the sun of the host's date is placed where the ownship is, not at
        [site], and positions 10, 100 and 1,000 km out agree with the Earth-centred
        computation above to a millimetre (the flat-earth projection was 1 km off at 100 km),
        in the database the world re-centred on the ownship (issue 48)."""
        d = self.start()
        c = d.client()

        def sun():
            regs = holding_registers(d)
            return unfloat(regs[22:24]), unfloat(regs[20:22])  # elevation, azimuth

        frame = 1
        for lat, lon in [(45.0, 0.0), (45.0, 10.0), (38.0, 10.0)]:
            self.frame(entity_control(0, lat, lon, 3000.0), celestial_control(6, 21, 2026, 12, 0),
                       frame=frame)
            frame += 1
            el, az = sun()
            want_el, want_az = sun_spencer(2026, 6, 21, 12, 0, lat, lon)
            # The azimuth from the database's north: the world re-centred on the ownship, its
            # grid north turned by the meridians' convergence on the way.
            site = c.ok({"cmd": "stats"})["site"]
            self.assertLess(math.dist(database(lat, lon, 0.0, site)[:2], (0.0, 0.0)), 1000.0)
            want_az += north_bearing(lat, lon, site)
            self.assertAlmostEqual(el, want_el, delta=0.3, msg=f"{lat}, {lon}")
            self.assertAlmostEqual(az % 360.0, want_az % 360.0, delta=0.5, msg=f"{lat}, {lon}")
        # The case: 45 N 0 E at noon UT on 21 June, 680 km from [site].
        self.frame(entity_control(0, 45.0, 0.0, 3000.0), frame=frame)
        frame += 1
        el, az = sun()
        self.assertAlmostEqual(el, 68.4, delta=0.3)
        site = c.ok({"cmd": "stats"})["site"]
        self.assertAlmostEqual(az, 179.0 + north_bearing(45.0, 0.0, site), delta=1.0)
        for km in (10.0, 100.0, 1000.0):
            lat, lon = SITE[0] + 0.6 * km / 111.2, SITE[1] + 0.8 * km / 69.2
            self.frame(entity_control(0, lat, lon, 2500.0), frame=frame)
            frame += 1
            front = c.ok({"cmd": "get_view", "view": "front"})
            east, north, up = database(lat, lon, 2500.0, c.ok({"cmd": "stats"})["site"])
            self.assertAlmostEqual(front["position"][0], east, delta=1e-3, msg=f"{km} km")
            self.assertAlmostEqual(front["position"][1], north, delta=1e-3, msg=f"{km} km")
            self.assertEqual(front["position"][2], up)

    def test_without_a_site_the_hosts_first_position_is_the_origin(self):
        """Issue 48, item 1: with no [site] the first message that places the ownship sets the
        database origin, for every position in it whatever the packets' order (a target sent
        before the ownship here); later motion is measured about it, 211.2 m flown north at 45 N
        is 211.2 m in the database, and the daemon says where the origin is."""
        d = self.start(site=False)
        c = d.client()
        origin = (45.0, 7.0)
        rib = (45.01, 7.02)
        self.frame(entity_control(5, *rib, 0.0), entity_control(0, *origin, 3000.0), frame=1)
        front = c.ok({"cmd": "get_view", "view": "front"})
        self.assertAlmostEqual(front["position"][0], 0.0, delta=1e-6)
        self.assertAlmostEqual(front["position"][1], 0.0, delta=1e-6)
        self.assertEqual(front["position"][2], 3000.0)
        targets = {t["name"]: t for t in c.ok({"cmd": "list_targets"})["targets"]}
        east, north, _ = enu(*rib, 0.0, *origin)
        self.assertAlmostEqual(targets["cigi-5"]["centre"][0], east, delta=1e-3)
        self.assertAlmostEqual(targets["cigi-5"]["centre"][1], north, delta=1e-3)
        # 211.2 m north along the meridian (the flight, which moved the view 149.3 m
        # with the origin at 0 N 0 E).
        lat = origin[0] + 211.2 / 111131.745
        self.frame(entity_control(0, lat, origin[1], 3000.0), frame=2)
        front = c.ok({"cmd": "get_view", "view": "front"})
        east, north, _ = enu(lat, origin[1], 3000.0, *origin)
        self.assertAlmostEqual(front["position"][1], north, delta=1e-3)
        self.assertAlmostEqual(front["position"][1], 211.2, delta=0.2)
        self.assertAlmostEqual(front["position"][0], 0.0, delta=1e-3)
        self.assertEqual(d.log_text().count("event=cigi_site"), 1)
        self.assertIn("latitude=45.000000 longitude=7.000000", d.log_text())

    def test_synchronous_mode_advances_by_the_host_frame_and_renders_once(self):
        d = self.start()
        c = d.client()
        sub = c.ok({"cmd": "subscribe", "view": "front", "rate": 60, "format": "raw"})
        first, _ = c.read()
        self.assertEqual(first["image"]["tick"], 0)
        t0 = c.ok({"cmd": "hash"})["time"]
        stamps = [200000, 201667, 203334, 205001]  # 10 microsecond units: 1/60 s apart
        for i, stamp in enumerate(stamps):
            self.frame(entity_control(0, SITE[0], SITE[1], 800.0 + i), frame=10 + i,
                       timestamp=stamp)
        ticks = []
        while len(ticks) < 4:
            header, body = c.read()
            self.assertEqual(header["event"], "frame")
            ticks.append(header["image"]["tick"])
            self.assertEqual(len(body), header["image"]["bytes"])
        self.assertEqual(ticks, [1, 2, 3, 4])
        state = c.ok({"cmd": "hash"})
        # The first frame has no earlier timestamp: one tick period (1/30 s); then 1/60 s each.
        self.assertAlmostEqual(state["time"] - t0, 1 / 30 + 3 * 0.01667, places=6)
        self.assertEqual(header["image"]["camera"]["position"][2], 803.0)
        c.ok({"cmd": "unsubscribe", "subscription": sub["subscription"]})

    def test_asynchronous_mode_announces_each_ig_frame_at_its_own_rate(self):
        """Issue 29, item 3: in asynchronous (realtime) mode the IG sends Start of Frame at the
        start of each of its own frames, at its rate (tick_rate 30), whatever the host sends;
        each reports the last host frame handled and what became of it."""
        d = self.start(mode="realtime")
        c = d.client()
        self.no_reply(0.3)  # no host has spoken: there is no one to announce to
        sofs = []

        def drain():
            self.host.setblocking(False)
            try:
                while True:
                    data, _ = self.host.recvfrom(65536)
                    sofs.append((time.monotonic(), decode_sof(data)))
            except BlockingIOError:
                pass
            finally:
                self.host.setblocking(True)
                self.host.settimeout(10)

        # A host sending at 200 Hz for a second: the IG still announces about 30 frames a
        # second, not one per host frame.
        started = time.monotonic()
        for n in range(1, 201):
            self.send(ig_control(n), entity_control(0, SITE[0], SITE[1], 500.0 + n))
            time.sleep(0.005)
            drain()
        while time.monotonic() < started + 1.5:
            time.sleep(0.02)
            drain()
        # A slow build (sanitizers) may still be working through the host's last frames.
        wait_until(lambda: drain() or (sofs and sofs[-1][1]["last_host_frame"] == 200),
                   "a Start of Frame reporting host frame 200")
        span = sofs[-1][0] - sofs[0][0]
        rate = (len(sofs) - 1) / span
        self.assertGreater(rate, 15, sofs[:5])
        self.assertLess(rate, 45, sofs[:5])
        numbers = [sof["ig_frame"] for _, sof in sofs]
        self.assertEqual(numbers, list(range(numbers[0], numbers[0] + len(numbers))))
        last = sofs[-1][1]
        self.assertEqual(last["last_host_frame"], 200)
        self.assertEqual(last["status"], 0)
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["position"][2], 700.0)
        # A host frame with a refused packet: the following frames say so, and name it.
        self.send(ig_control(201), entity_control(0, SITE[0], SITE[1], 900.0),
                  weather_control(1, True, 7, coverage=150.0, base=1500.0, thickness=800.0))
        wait_until(lambda: drain() or (sofs[-1][1]["last_host_frame"] == 201),
                   "a Start of Frame for host frame 201")
        self.assertEqual(sofs[-1][1]["status"], 1)
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["position"][2], 900.0)
        # Paused, the world holds its time, but its frames go on.
        c.ok({"cmd": "set_time", "paused": True})
        count = len(sofs)
        time.sleep(0.5)
        drain()
        self.assertGreater(len(sofs) - count, 5)

    def test_regional_weather_is_drawn_in_its_region(self):
        """Issue 29, item 2: Weather Control of regional scope is drawn inside the rectangle
        an Environmental Region Control makes active (rotation, transition perimeter), kept
        while the region is inactive, moved with it and removed when it is destroyed."""
        d = self.start()
        c = d.client()
        lat0, lon0 = SITE[0] + 0.05, SITE[1]  # the region's centre, about 5.6 km north
        north = enu(lat0, lon0, 0.0, *SITE)[1]

        def covered(east, y):
            """Mean coverage seen straight down from 6 km over (east, y)."""
            c.ok({"cmd": "set_view", "view": "front", "position": [east, y, 6000.0],
                  "pitch": -90.0, "vfov": 30.0})
            _, raw = c.ok({"cmd": "render", "view": "front", "format": "raw",
                           "channels": ["coverage"]})
            return sum(raw) / (255.0 * len(raw))

        overcast = weather_control(1, True, 10, coverage=100.0, base=1000.0, thickness=300.0,
                                   scope=1, region=9)
        # Regional weather for a region no packet has made active is kept, not drawn.
        self.frame(overcast, frame=1)
        self.assertEqual(covered(0.0, north), 0.0)
        self.assertEqual(c.ok({"cmd": "stats"})["cigi"]["ignored"], 1)
        # Region 9: 10 km along its X axis (turned 90 degrees: east) by 4 km, 1 km perimeter.
        self.frame(region_control(9, 1, lat0, lon0, 10000.0, 4000.0, rotation=90.0,
                                  perimeter=1000.0), frame=2)
        self.assertGreater(covered(0.0, north), 0.99)   # its centre
        self.assertGreater(covered(3000.0, north), 0.99)  # 3 km east: within its 5 km half length
        self.assertEqual(covered(0.0, north + 4500.0), 0.0)  # 4.5 km north: beyond 2 + 1 km
        self.assertEqual(covered(0.0, -30000.0), 0.0)  # no global layer
        # The same packets again change nothing; moving the region moves its weather.
        ticks = c.ok({"cmd": "hash"})["ticks"]
        self.frame(region_control(9, 1, lat0, lon0, 10000.0, 4000.0, rotation=90.0,
                                  perimeter=1000.0), frame=3)
        self.frame(region_control(9, 1, lat0 + 0.1, lon0, 10000.0, 4000.0, rotation=90.0,
                                  perimeter=1000.0), frame=4)
        self.assertEqual(covered(0.0, north), 0.0)
        self.assertGreater(covered(0.0, enu(lat0 + 0.1, lon0, 0.0, *SITE)[1]), 0.99)
        self.assertEqual(c.ok({"cmd": "hash"})["ticks"], ticks + 2)
        # Inactive: not drawn, but kept; active again: drawn again; destroyed: gone for good.
        self.frame(region_control(9, 0, lat0, lon0, 10000.0, 4000.0), frame=5)
        self.assertEqual(covered(0.0, north), 0.0)
        self.frame(region_control(9, 1, lat0, lon0, 10000.0, 4000.0, rotation=90.0,
                                  perimeter=1000.0), frame=6)
        self.assertGreater(covered(0.0, north), 0.99)
        self.frame(region_control(9, 2, lat0, lon0, 10000.0, 4000.0), frame=7)
        self.assertEqual(covered(0.0, north), 0.0)
        self.frame(region_control(9, 1, lat0, lon0, 10000.0, 4000.0), frame=8)
        self.assertEqual(covered(0.0, north), 0.0)
        # A region out of range is refused alone; entity scope is still ignored.
        sof = self.frame(region_control(3, 1, 95.0, lon0, 1000.0, 1000.0), frame=9)
        self.assertEqual(sof["status"], 1)
        self.assertIn("latitude 95", d.log_text())
        self.check_with_tshark()

    def test_in_layer_visibility_and_transition_band_are_drawn(self):
        """Issue 29, item 2: Weather Control's visibility within a cloud layer is the density
        of the veil a view inside the layer looks through, and its transition band thins that
        veil above the top and below the base (MODEL.md section 5)."""
        d = self.start()
        c = d.client()

        def inside(z, visibility, band, frame):
            self.frame(weather_control(1, True, 10, coverage=100.0, base=600.0, thickness=500.0,
                                       visibility=visibility, transition=band), frame=frame)
            # 20 km west of the scene's cumulus, whose own veil would fill the view.
            c.ok({"cmd": "set_view", "view": "front", "position": [-20000.0, 0.0, z],
                  "heading": 270.0, "pitch": 10.0, "vfov": 60.0})
            _, raw = c.ok({"cmd": "render", "view": "front", "format": "raw",
                           "channels": ["colour"]})
            green = raw[1::3]
            return max(green) - min(green)

        # In the deck: a 50 m veil hides its planes, a 5 km one shows them.
        self.assertLessEqual(inside(850.0, 50.0, 0.0, 1), 2)
        self.assertGreater(inside(850.0, 5000.0, 0.0, 2), 10)
        # 50 m above the top: a 300 m band still veils the view, no band leaves the planes.
        self.assertLessEqual(inside(1150.0, 50.0, 300.0, 3), 2)
        self.assertGreater(inside(1150.0, 50.0, 0.0, 4), 10)
        self.assertNotIn("ignored", c.ok({"cmd": "stats"})["cigi"])
        # Scud: fragments under the base (MODEL.md section 10), at the frequency asked; looking
        # up from under them the view varies more than under the bare deck. 150 % refuses the
        # packet, which changes nothing.
        def under(scud, frame, send=True):
            self.frame(weather_control(1, True, 10, coverage=100.0, base=600.0, thickness=500.0,
                                       transition=300.0, scud=scud) if send else b"", frame=frame)
            c.ok({"cmd": "set_view", "view": "front", "position": [-20000.0, 0.0, 2.0],
                  "heading": 270.0, "pitch": 40.0, "vfov": 60.0})
            _, raw = c.ok({"cmd": "render", "view": "front", "format": "raw",
                           "channels": ["colour"]})
            green = raw[1::3]
            return max(green) - min(green)
        bare = under(None, 5)
        with_scud = under(40.0, 6)
        self.assertGreater(with_scud, bare + 10)
        self.frame(weather_control(1, True, 10, coverage=100.0, base=600.0, thickness=500.0,
                                   scud=150.0), frame=7)
        self.assertEqual(under(None, 8, send=False), with_scud)  # the refused packet: no change
        self.assertNotIn("ignored", c.ok({"cmd": "stats"})["cigi"])
        # Precipitation (MODEL.md section 17): layer 4, rain from the ground to 600 m at the
        # rate of severity 5 (75 mm/h, 500 m of visibility), veils the view along the ground;
        # disabled, the view is as before.
        def level(frame, *packets):
            self.frame(*packets, frame=frame)
            c.ok({"cmd": "set_view", "view": "front", "position": [-20000.0, 0.0, 2.0],
                  "heading": 270.0, "pitch": -2.0, "vfov": 20.0})
            _, raw = c.ok({"cmd": "render", "view": "front", "format": "raw",
                           "channels": ["colour"]})
            green = raw[1::3]
            return max(green) - min(green)
        dry = level(9, weather_control(1, False))
        wet = level(10, weather_control(4, True, base=0.0, thickness=600.0, severity=5))
        self.assertLess(wet, dry)
        self.assertEqual(level(11, weather_control(4, False)), dry)
        self.assertNotIn("ignored", c.ok({"cmd": "stats"})["cigi"])

    def test_the_sea_from_maritime_surface_conditions_and_wave_control(self):
        """Maritime Surface Conditions Control (13) and Wave Control (14) of global scope set
        the sea (set_sea reads it back): clarity from percent, each wave train as sent (its
        direction is where it travels, as the sea's), the wind the surface wind. What the sea
        does not model is ignored with its reason; packets repeated every frame change nothing."""
        d = self.start()
        c = d.client()
        self.assertEqual(c.ok({"cmd": "set_sea"}), {"enabled": False})
        self.frame(atmosphere_control(0.0, 8.0, 270.0),  # 8 m/s from the west
                   maritime_control(True, True, 12.5, 70.0, height=1.5),
                   wave_control(3, True, 2.0, 150.0, 9.0, 45.0, phase=30.0, leading=10.0,
                                breaker=1),
                   wave_control(5, True, 0.5, 20.0, 0.0, 200.0),
                   maritime_control(True, False, 30.0, 10.0, scope=1, region=4),
                   wave_control(6, True, scope=2, region=7),
                   frame=1, timestamp=100000)
        sea = c.ok({"cmd": "set_sea"})
        self.assertTrue(sea["enabled"])
        self.assertAlmostEqual(sea["wind"][0], 8.0, places=9)
        self.assertAlmostEqual(sea["wind"][1], 0.0, places=9)
        self.assertEqual((sea["temperature"], sea["whitecaps"]), (12.5, True))
        self.assertAlmostEqual(sea["clarity"], 0.7, places=12)
        self.assertEqual(sea["waves"], [
            {"id": 3, "height": 2.0, "wavelength": 150.0, "period": 9.0, "direction": 45.0,
             "phase": 30.0},
            {"id": 5, "height": 0.5, "wavelength": 20.0, "period": 0.0, "direction": 200.0,
             "phase": 0.0}])
        # Ignored, each with its reason: the surface height, breaker type and leading, and the
        # regional and entity packets.
        stats = c.ok({"cmd": "stats"})["cigi"]
        self.assertEqual(stats["ignored"], 5, stats)
        self.assertNotIn("refused_bad_value", stats)
        # The same packets again: no change and nothing more ignored; a train disabled goes.
        self.frame(maritime_control(True, True, 12.5, 70.0, height=1.5),
                   wave_control(3, True, 2.0, 150.0, 9.0, 45.0, phase=30.0, leading=10.0,
                                breaker=1),
                   wave_control(5, False), frame=2, timestamp=101667)
        self.assertEqual(c.ok({"cmd": "stats"})["cigi"]["ignored"], 5)
        self.assertEqual([w["id"] for w in c.ok({"cmd": "set_sea"})["waves"]], [3])
        # The sea's wind follows the host's wind.
        self.frame(atmosphere_control(0.0, 6.0, 0.0), frame=3, timestamp=103334)  # from north
        wind = c.ok({"cmd": "set_sea"})["wind"]
        self.assertAlmostEqual(wind[0], 0.0, places=9)
        self.assertAlmostEqual(wind[1], -6.0, places=9)
        # Surface conditions disabled: no sea. Enabled again, the host's trains come back.
        self.frame(maritime_control(False, False, 0.0, 0.0), frame=4, timestamp=105001)
        self.assertEqual(c.ok({"cmd": "set_sea"}), {"enabled": False})
        self.frame(maritime_control(True, False, 4.0, 100.0), frame=5, timestamp=106668)
        sea = c.ok({"cmd": "set_sea"})
        self.assertEqual((sea["temperature"], sea["clarity"], sea["whitecaps"]),
                         (4.0, 1.0, False))
        self.assertEqual([w["id"] for w in sea["waves"]], [3])
        # Out of range: that packet is refused (IG status 1), the rest of the frame applies.
        sof = self.frame(maritime_control(True, False, 50.0, 100.0),
                         wave_control(8, True, 1.0, 0.5), wave_control(9, True, 0.25, 10.0),
                         frame=6, timestamp=108335)
        self.assertEqual(sof["status"], 1)
        sea = c.ok({"cmd": "set_sea"})
        self.assertEqual(sea["temperature"], 4.0)
        self.assertEqual([w["id"] for w in sea["waves"]], [3, 9])
        self.assertEqual(c.ok({"cmd": "stats"})["cigi"]["refused_bad_value"], 2)
        self.check_with_tshark()

    def test_little_endian_host(self):
        d = self.start()
        c = d.client()
        sof = self.frame(entity_control(0, SITE[0], SITE[1], 950.0, yaw=45.0, bo="<"),
                         weather_control(2, True, 9, coverage=60.0, base=2000.0,
                                         thickness=300.0, bo="<"),
                         frame=5, timestamp=1000, bo="<")
        self.assertEqual(sof["order"], "<")  # answered in the host's byte order
        front = c.ok({"cmd": "get_view", "view": "front"})
        self.assertEqual((front["position"], front["heading"]), ([0, 0, 950.0], 45.0))
        self.check_with_tshark()

    def test_bad_datagrams_change_nothing_and_are_counted(self):
        d = self.start()
        c = d.client()
        self.frame(entity_control(0, SITE[0], SITE[1], 500.0), frame=100, timestamp=1)
        before = c.ok({"cmd": "hash"})
        good = ig_control(101, 2) + entity_control(0, SITE[0], SITE[1], 999.0)
        bad = {
            "truncated": [good[:10], good[:40],
                          ig_control(101, 2) + entity_control(0, 0, 0, 0)[:24] + b"\0" * 8],
            "oversized": [good + (struct.pack(">BB", 200, 8) + b"\0" * 6) * 4200],
            "wrong_version": [ig_control(101, 2, version=2) + good[24:]],
            "bad_magic": [good[:6] + b"\x12\x34" + good[8:]],
            "wrong_first_packet": [good[24:] + good[:24], b"\x65\x18" + good[2:24]],
            "malformed": [good + b"\x02\x07" + b"\0" * 6, good + b"\x02\x00" + b"\0" * 6,
                          good + good[:24],
                          good[:24] + struct.pack(">BB", 2, 40) + good[26:64]],
            "out_of_order": [ig_control(100, 2) + good[24:], ig_control(99, 2) + good[24:]],
        }
        for reason, datagrams in bad.items():
            for data in datagrams:
                with self.subTest(reason=reason, size=len(data)):
                    self.host.sendto(data, ("127.0.0.1", self.ig_port))
                    if reason == "out_of_order":  # a valid IG Control: answered, IG status 2
                        sof = self.receive_sof()
                        self.assertEqual((sof["status"], sof["last_host_frame"]),
                                         (2, struct.unpack(">I", data[8:12])[0]))
                    else:
                        self.no_reply()
        after = c.ok({"cmd": "hash"})
        self.assertEqual(after["hash"], before["hash"])
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["position"][2], 500.0)
        stats = c.ok({"cmd": "stats"})["cigi"]
        for reason, datagrams in bad.items():
            self.assertEqual(stats.get("refused_" + reason), len(datagrams), (reason, stats))
        self.assertIn("event=cigi_refused reason=wrong_version", d.log_text())
        # The daemon still answers the host, in order.
        self.frame(entity_control(0, SITE[0], SITE[1], 999.0), frame=101, timestamp=2)
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["position"][2], 999.0)

    def test_case16_a_host_that_restarts_its_frame_numbers_is_followed_within_3_frames(self):
        """Issue 26: after a host restarted its frame numbers (the CIGI Class Library counts
        from 0), or after one corrupted number, every later frame was refused as late."""
        d = self.start()
        c = d.client()

        def altitude():
            return c.ok({"cmd": "get_view", "view": "front"})["position"][2]

        for n in range(30):  # the host's first run
            self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 100.0 + n),
                                        frame=n)["status"], 0)
        # The same program started again: numbers from 0. The first frame is refused as a jump
        # (IG status 3), the second confirms the new run and applies.
        sof = self.frame(entity_control(0, SITE[0], SITE[1], 500.0), frame=0)
        self.assertEqual(sof["status"], 3)
        self.assertEqual(altitude(), 129.0)
        for n in range(1, 10):
            self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 500.0 + n),
                                        frame=n)["status"], 0, n)
            self.assertEqual(altitude(), 500.0 + n)
        # A restart soon after the last one, within the reordering window: the third
        # consecutive number applies.
        statuses = [self.frame(entity_control(0, SITE[0], SITE[1], 700.0 + n), frame=n)["status"]
                    for n in range(3)]
        self.assertEqual(statuses, [2, 2, 0])
        self.assertEqual(altitude(), 702.0)
        # One corrupted frame number, far ahead or far behind: refused, and the host's next
        # frames go on as before.
        for corrupt in (0x7FFFFFF0, 0x80000000 + 5):
            self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 900.0),
                                        frame=corrupt)["status"], 3)
        self.assertEqual(altitude(), 702.0)
        self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 703.0), frame=3)["status"], 0)
        self.assertEqual(altitude(), 703.0)
        # Late and repeated datagrams within the window are still refused and counted.
        self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 1.0), frame=3)["status"], 2)
        self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 1.0), frame=1)["status"], 2)
        self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 704.0), frame=4)["status"], 0)
        self.assertEqual(altitude(), 704.0)
        stats = c.ok({"cmd": "stats"})["cigi"]
        self.assertEqual(stats["refused_frame_jump"], 3, stats)
        self.assertEqual(stats["refused_out_of_order"], 4, stats)

    def test_case17_a_frame_with_one_refused_packet_gets_start_of_frame_and_its_valid_packets_apply(self):
        """Issue 26: a frame with one value out of range (coverage 150 %) got no Start of Frame
        and its ownship move was lost; a synchronous host waits for Start of Frame."""
        d = self.start()
        c = d.client()
        self.frame(entity_control(0, SITE[0], SITE[1], 500.0), frame=1, timestamp=1)
        bad = [weather_control(1, True, 7, coverage=150.0, base=1500.0, thickness=800.0),
               entity_control(7, 95.0, 0, 10),
               weather_control(1, True, 12, 50, 1000, 500),
               celestial_control(2, 30, 2026, 12, 0),
               entity_control(7, SITE[0], SITE[1], float("nan")),
               view_definition(0, 30, -30, 20, -20)]
        for k, packet in enumerate(bad):
            with self.subTest(packet=k):
                sof = self.frame(entity_control(0, SITE[0], SITE[1], 600.0 + k), packet,
                                 frame=2 + k, timestamp=2 + k)
                self.assertEqual(sof["status"], 1)  # some packets refused, the rest applied
                view = c.ok({"cmd": "get_view", "view": "front"})
                self.assertEqual(view["position"][2], 600.0 + k)
        self.assertEqual(c.ok({"cmd": "list_targets"})["targets"], [])
        stats = c.ok({"cmd": "stats"})["cigi"]
        self.assertEqual(stats["refused_bad_value"], len(bad), stats)
        self.assertIn("event=cigi_refused reason=bad_value", d.log_text())
        # A frame of valid packets only is answered with IG status 0.
        self.assertEqual(self.frame(entity_control(0, SITE[0], SITE[1], 700.0), frame=20)["status"],
                         0)

    def test_case17_an_entity_refused_for_its_position_is_placed_when_it_comes_back(self):
        """An entity refused for a position beyond the world's range was kept as placed, so
        the host's next, valid Entity Control for it became a move of a target that did not
        exist, and the world refused that whole frame (its ownship move too)."""
        d = self.start()
        c = d.client()
        self.frame(entity_control(0, SITE[0], SITE[1], 500.0), frame=1, timestamp=1)
        sof = self.frame(entity_control(7, SITE[0], SITE[1], 2e8), frame=2, timestamp=2)
        self.assertEqual(sof["status"], 1)
        self.assertEqual(c.ok({"cmd": "list_targets"})["targets"], [])
        sof = self.frame(entity_control(0, SITE[0], SITE[1], 600.0),
                         entity_control(7, SITE[0], SITE[1], 20.0), frame=3, timestamp=3)
        self.assertEqual(sof["status"], 0, c.ok({"cmd": "stats"})["cigi"])
        self.assertEqual([t["name"] for t in c.ok({"cmd": "list_targets"})["targets"]],
                         ["cigi-7"])
        self.assertEqual(c.ok({"cmd": "get_view", "view": "front"})["position"][2], 600.0)

    def check_with_tshark(self):
        """Every datagram of the test, decoded by Wireshark's CIGI dissector: its fields must
        be the ones the host wrote and read."""
        fields = ["cigi.packet_id", "cigi.version", "cigi.byte_swap",
                  "cigi.ig_control.frame_ctr", "cigi.ig_control.host_frame_number",
                  "cigi.ig_control.minor_version",
                  "cigi.entity_control.entity_id", "cigi.entity_control.entity_type",
                  "cigi.entity_control.yaw", "cigi.entity_control.lat_xoff",
                  "cigi.entity_control.alt_zoff", "cigi.entity_control.entity_state",
                  "cigi.view_def.view_id", "cigi.view_def.top", "cigi.view_def.left",
                  "cigi.view_control.view_id", "cigi.view_control.entity_id",
                  "cigi.view_control.yaw",
                  "cigi.weather_control.layer_id", "cigi.weather_control.cloud_type",
                  "cigi.weather_control.coverage", "cigi.weather_control.elevation",
                  "cigi.weather_control.thickness", "cigi.weather_control.visibility_range",
                  "cigi.atmosphere_control.horiz_wind",
                  "cigi.env_region_control.region_id",
                  "cigi.env_region_control.lat",
                  "cigi.env_region_control.size_x",
                  "cigi.env_region_control.rotation",
                  "cigi.celestial_sphere_control.date", "cigi.celestial_sphere_control.hour",
                  "cigi.maritime_surface_conditions_control.entity_region_id",
                  "cigi.maritime_surface_conditions_control.surface_conditions_enable",
                  "cigi.maritime_surface_conditions_control.scope",
                  "cigi.maritime_surface_conditions_control.sea_surface_height",
                  "cigi.maritime_surface_conditions_control.surface_water_temp",
                  "cigi.maritime_surface_conditions_control.surface_clarity",
                  "cigi.wave_control.wave_id", "cigi.wave_control.wave_enable",
                  "cigi.wave_control.scope", "cigi.wave_control.breaker_type",
                  "cigi.wave_control.height", "cigi.wave_control.wavelength",
                  "cigi.wave_control.period", "cigi.wave_control.direction",
                  "cigi.wave_control.phase_offset", "cigi.wave_control.leading",
                  "cigi.sof.ig_frame_number",
                  "cigi.sof.last_host_frame_number",
                  "cigi.sof.minor_version", "cigi.sof.ig_mode"]
        path = os.path.join(self.tmp.name, "cigi.pcap")
        decoded = self.capture.dissect(path, [self.ig_port, self.host_port], fields)
        self.assertEqual(len(decoded), len(self.capture.records))
        for layers, frame in zip(decoded, self.capture.records):
            payload = frame[14 + 20 + 8:]
            with self.subTest(first_packet=payload[0]):
                self.assertEqual(layers["cigi.version"], ["3"])
                ids, sizes, at = [], [], 0
                while at < len(payload):  # the packets as laid out in the bytes
                    ids.append(str(payload[at]))
                    at += payload[at + 1]
                self.assertEqual(layers["cigi.packet_id"], ids)
                bo = ">" if payload[6:8] == b"\x80\x00" else "<"
                if payload[0] == 101:  # Start of Frame, from Nephele
                    sof = decode_sof(payload)
                    self.assertEqual(layers["cigi.sof.ig_frame_number"],
                                     [str(sof["ig_frame"])])
                    self.assertEqual(layers["cigi.sof.last_host_frame_number"],
                                     [str(sof["last_host_frame"])])
                    self.assertEqual(layers["cigi.sof.minor_version"], ["3"])
                    continue
                (frame_number,) = struct.unpack(bo + "I", payload[8:12])
                self.assertEqual(layers["cigi.ig_control.host_frame_number"], [str(frame_number)])
                at = 24
                entity_ids, types, yaws, weather_layers, coverages = [], [], [], [], []
                regions = []  # Environmental Region Control: id, latitude, size X, rotation
                maritimes, waves = [], []  # as the host wrote them, fields in the ICD's order
                while at < len(payload):
                    pid = payload[at]
                    if pid == 2:
                        (eid,) = struct.unpack(bo + "H", payload[at + 2:at + 4])
                        (etype,) = struct.unpack(bo + "H", payload[at + 8:at + 10])
                        (yaw,) = struct.unpack(bo + "f", payload[at + 20:at + 24])
                        entity_ids.append(str(eid))
                        types.append(str(etype))
                        yaws.append(float(yaw))
                    if pid == 11:
                        (rid,) = struct.unpack(bo + "H", payload[at + 2:at + 4])
                        (rlat,) = struct.unpack(bo + "d", payload[at + 8:at + 16])
                        size_x, _, _, rotation = struct.unpack(bo + "4f", payload[at + 24:at + 40])
                        regions.append((rid, rlat, size_x, rotation))
                    if pid == 13:
                        (region,) = struct.unpack(bo + "H", payload[at + 2:at + 4])
                        flags = payload[at + 4]
                        maritimes.append((region, flags & 1, (flags >> 2) & 3) + struct.unpack(
                            bo + "3f", payload[at + 8:at + 20]))
                    if pid == 14:
                        flags = payload[at + 5]
                        waves.append((payload[at + 4], flags & 1, (flags >> 1) & 3,
                                      (flags >> 3) & 3) + struct.unpack(
                                          bo + "6f", payload[at + 8:at + 32]))
                    if pid == 12:
                        weather_layers.append(str(payload[at + 4]))
                        coverages.append(struct.unpack(bo + "f", payload[at + 20:at + 24])[0])
                    at += payload[at + 1]
                self.assertEqual(layers.get("cigi.entity_control.entity_id", []), entity_ids)
                self.assertEqual(layers.get("cigi.entity_control.entity_type", []), types)
                self.assertEqual([float(v) for v in layers.get("cigi.entity_control.yaw", [])],
                                 yaws)
                self.assertEqual(layers.get("cigi.weather_control.layer_id", []), weather_layers)
                self.assertEqual([float(v) for v in
                                  layers.get("cigi.weather_control.coverage", [])], coverages)
                names = ["region_id", "lat", "size_x", "rotation"]
                dissected = [[float(v) for v in
                              layers.get("cigi.env_region_control." + n, [])]
                             for n in names]
                self.assertEqual(list(zip(*dissected)), [tuple(map(float, r)) for r in regions])
                names = ["entity_region_id", "surface_conditions_enable", "scope",
                         "sea_surface_height", "surface_water_temp", "surface_clarity"]
                dissected = [[dissected_number(v) for v in
                              layers.get("cigi.maritime_surface_conditions_control." + n, [])]
                             for n in names]
                self.assertEqual(list(zip(*dissected)),
                                 [tuple(map(float, m)) for m in maritimes])
                names = ["wave_id", "wave_enable", "scope", "breaker_type", "height",
                         "wavelength", "period", "direction", "phase_offset", "leading"]
                dissected = [[dissected_number(v) for v in
                              layers.get("cigi.wave_control." + n, [])] for n in names]
                self.assertEqual(list(zip(*dissected)), [tuple(map(float, w)) for w in waves])


if __name__ == "__main__":
    unittest.main()
