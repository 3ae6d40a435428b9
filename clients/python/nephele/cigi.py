"""A CIGI 3.3 host over UDP, for scripts that drive the daemon as a host simulator would
(docs/CIGI.md): IG Control, Entity Control, Atmosphere Control and Celestial Sphere Control
out, Start of Frame back.

Packet layouts are the CIGI 3.3 ICD's (SISO-STD-013), written big-endian (the daemon answers in
the sender's byte order). Each host frame is one datagram: IG Control, then the frame's packets.

    with CigiHost("127.0.0.1", ig_port) as host:
        reply = host.frame(entity_control(0, latitude=51.5, longitude=-1.25, altitude=500,
                                          yaw=90),
                           atmosphere_control(visibility=20000, wind_speed=8,
                                              wind_direction=270))
        assert reply.last_host_frame == host.host_frame and reply.ig_status == 0
"""
from __future__ import annotations

import enum
import socket
import struct
import time
from dataclasses import dataclass

from .errors import RequestTimeout

MAJOR_VERSION = 3
MINOR_VERSION = 3
MAGIC = 0x8000  # the byte-swap magic number, read in either byte order by the IG
TIMESTAMP_TICKS_PER_SECOND = 100_000  # IG Control and Start of Frame timestamps: 10 us units

_ORDER = ">"  # the byte order this host writes
_IG_CONTROL = struct.Struct(_ORDER + "BBBbBBHIII4x")  # 1: 24 bytes
_ENTITY_CONTROL = struct.Struct(_ORDER + "BBHBBBBHHfffddd")  # 2: 48 bytes
_CELESTIAL_SPHERE_CONTROL = struct.Struct(_ORDER + "BBBBB3xIf")  # 9: 16 bytes
_ATMOSPHERE_CONTROL = struct.Struct(_ORDER + "BBBBffffff4x")  # 10: 32 bytes
_START_OF_FRAME_ID, _START_OF_FRAME_SIZE = 101, 24


class IgMode(enum.IntEnum):
    """IG Control's IG mode."""

    STANDBY = 0  # reset/standby: nothing in the message applies but its number and time
    OPERATE = 1
    DEBUG = 2


class EntityState(enum.IntEnum):
    INACTIVE = 0
    ACTIVE = 1
    DESTROYED = 2


def ig_control(host_frame: int, mode: IgMode = IgMode.OPERATE, timestamp: int | None = None,
               database: int = 0, last_ig_frame: int = 0) -> bytes:
    """IG Control (identifier 1), the first packet of every host message. `timestamp` is in
    10 microsecond units (None: not valid); in lockstep the daemon ticks by the difference of
    two valid timestamps, else by one tick period."""
    flags = int(mode) | (timestamp is not None) << 2 | MINOR_VERSION << 4
    return _IG_CONTROL.pack(1, _IG_CONTROL.size, MAJOR_VERSION, database, flags, 0, MAGIC,
                            host_frame, timestamp or 0, last_ig_frame)


def entity_control(entity: int, latitude: float, longitude: float, altitude: float,
                   yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0,
                   state: EntityState = EntityState.ACTIVE, entity_type: int = 0,
                   attached: bool = False, parent: int = 0) -> bytes:
    """Entity Control (identifier 2). Entity 0 is the ownship, which carries the views; others
    become targets drawn as the config's [[entity_type]] of `entity_type`. Latitude and
    longitude in degrees (WGS 84), altitude in metres above the ground plane, yaw (heading,
    clockwise from north), pitch and roll in degrees. An attached entity gives its offsets in
    its parent's body frame (x forward, y right, z down, metres) as latitude, longitude,
    altitude."""
    flags = int(state) | int(attached) << 2
    return _ENTITY_CONTROL.pack(2, _ENTITY_CONTROL.size, entity, flags, 0, 255, 0, entity_type,
                                parent, roll, pitch, yaw, latitude, longitude, altitude)


def celestial_sphere_control(year: int, month: int, day: int, hour: int, minute: int) -> bytes:
    """Celestial Sphere Control (identifier 9): the date and time (UTC) that place the sun, at
    the ownship. Ephemeris, sun, moon and stars are enabled and the date is marked valid."""
    enables = 0b11111  # ephemeris, sun, moon, star field, date/time valid
    date = month * 1_000_000 + day * 10_000 + year  # MMDDYYYY
    return _CELESTIAL_SPHERE_CONTROL.pack(9, _CELESTIAL_SPHERE_CONTROL.size, hour, minute,
                                          enables, date, 0.0)


def atmosphere_control(visibility: float = 0.0, wind_speed: float = 0.0,
                       wind_direction: float = 0.0, humidity: int = 50,
                       air_temperature: float = 15.0, pressure: float = 1013.25) -> bytes:
    """Atmosphere Control (identifier 10): the distance haze's visibility in metres (0 removes
    it), and the wind at every altitude, speed m/s and the direction it blows from (degrees
    clockwise from north). Humidity (%), air temperature (degrees C) and pressure (mb) are
    sent as the ICD has them and ignored by the daemon."""
    return _ATMOSPHERE_CONTROL.pack(10, _ATMOSPHERE_CONTROL.size, 1, humidity, air_temperature,
                                    visibility, wind_speed, 0.0, wind_direction, pressure)


@dataclass(frozen=True)
class StartOfFrame:
    """Start of Frame (identifier 101), the IG's answer: `ig_status` says what became of the
    host frame `last_host_frame` (0 applied, 1 some packets refused, 2 late or repeated, 3 a
    jump in numbering, 4 refused by the world, 5 the daemon was busy; docs/CIGI.md)."""

    database: int
    ig_status: int
    ig_mode: IgMode
    timestamp_valid: bool
    minor_version: int
    ig_frame: int
    timestamp: int  # 10 microsecond units since the daemon started
    last_host_frame: int

    @staticmethod
    def decode(datagram: bytes) -> StartOfFrame:
        """The Start of Frame that begins `datagram`, in the byte order of its magic number."""
        if len(datagram) < _START_OF_FRAME_SIZE or datagram[0] != _START_OF_FRAME_ID:
            raise ValueError(f"not a Start of Frame: {datagram[:_START_OF_FRAME_SIZE].hex()}")
        order = ">" if datagram[6:8] == MAGIC.to_bytes(2, "big") else "<"
        (_, _, _, database, status, flags, _, ig_frame, timestamp,
         last_host_frame) = struct.unpack(order + "BBBbBBHIII4x", datagram[:24])
        return StartOfFrame(database, status, IgMode(flags & 3), bool(flags & 4), flags >> 4,
                            ig_frame, timestamp, last_host_frame)


class CigiHost:
    """A host's UDP socket: sends host messages to the daemon's `[cigi] ig_port` and receives
    its Start of Frame replies, which go to this socket's address at the daemon's `host_port`
    (0 there: to this socket's own port). `port` is this socket's, 0 for any.

    `host_frame` numbers the messages sent, from 1; `timeout` (seconds) bounds a wait for Start
    of Frame. Each message's timestamp advances by the `dt` it is sent with, or else by the real
    time since the last one: a lockstep daemon ticks by that difference.
    """

    def __init__(self, address: str, ig_port: int, port: int = 0,
                 timeout: float | None = 10.0) -> None:
        self.address = (address, ig_port)
        self.timeout = timeout
        self.host_frame = 0
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.bind(("", port))
        self._clock = 0.0  # seconds: the timestamp of the last message
        self._last_sent = time.monotonic()

    def __enter__(self) -> CigiHost:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        self._socket.close()

    def send(self, *packets: bytes, mode: IgMode = IgMode.OPERATE,
             dt: float | None = None) -> int:
        """Sends the next host frame: IG Control, then `packets`; returns its frame number.
        Its timestamp is the last one plus `dt` seconds, or plus the real time since the last
        message without it."""
        self.host_frame += 1
        now = time.monotonic()
        self._clock += dt if dt is not None else now - self._last_sent
        self._last_sent = now
        timestamp = round(self._clock * TIMESTAMP_TICKS_PER_SECOND) % (1 << 32)
        message = ig_control(self.host_frame, mode, timestamp) + b"".join(packets)
        self._socket.sendto(message, self.address)
        return self.host_frame

    def receive(self) -> StartOfFrame:
        """The next Start of Frame, within `timeout`."""
        self._socket.settimeout(self.timeout)
        try:
            datagram, _ = self._socket.recvfrom(65536)
        except socket.timeout as e:
            raise RequestTimeout("no Start of Frame from the IG in time") from e
        return StartOfFrame.decode(datagram)

    def frame(self, *packets: bytes, mode: IgMode = IgMode.OPERATE,
              dt: float | None = None) -> StartOfFrame:
        """Sends a host frame and returns the Start of Frame that answers it (earlier ones are
        skipped): a synchronous (lockstep) host's step."""
        sent = self.send(*packets, mode=mode, dt=dt)
        while (reply := self.receive()).last_host_frame != sent:
            pass
        return reply
