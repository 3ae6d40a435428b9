"""The socket protocol's commands (PROTOCOL.md, "Commands"), one method each.

Every method sends one request and waits for its reply. Its keyword arguments are the
command's fields, named as on the wire; an argument left at None is not sent, so the daemon
keeps or defaults that field. Ranges are checked by the daemon, whose refusal is raised as a
NepheleError with its code and message. Angles are in degrees, positions in metres in the
world frame (X east, Y north, Z up), times in seconds.
"""
from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from typing import Any, overload

from .connection import Connection, JsonObject, deadline_after, image_header, request_line
from .errors import NepheleError
from .frame import Frame

DEFAULT_PORT = 7600


def _rendered_frame(message: JsonObject, data: bytearray | None) -> Frame:
    image = image_header(message)
    if image is None or data is None:
        raise ValueError(f"a render reply without an image: {message}")
    return Frame(image, data, None)


class Subscription:
    """The frames of one view that `Client.subscribe` asked for, in the order they came.

    Iterate over it to receive them: each `next()` returns a queued frame or waits for the next
    one, up to the client's `timeout`. Frames that arrive while the client waits for other
    replies are queued, at most `Client.queued_frames` of them; older ones are dropped and
    counted in `dropped`. The iteration ends once the subscription is closed (`close()`,
    `Client.unsubscribe`) or its connection is. In lockstep mode a frame comes only with a tick:
    call `Client.tick` between frames.
    """

    def __init__(self, client: Client, subscription: int, reply: JsonObject,
                 queued_frames: int) -> None:
        self.id = subscription
        self.reply = reply  # the subscribe reply: subscription, view, rate, format, channels
        self.dropped = 0
        self.active = True
        self._client = client
        self._frames: deque[Frame] = deque(maxlen=queued_frames)

    def __iter__(self) -> Iterator[Frame]:
        return self

    def __next__(self) -> Frame:
        if self.active and not self._frames:
            self._client._wait_for_frame(self)
        if not self._frames:
            raise StopIteration
        return self._frames.popleft()

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        """Unsubscribes, if the subscription is still active; queued frames are dropped."""
        if self.active and self._client.connected:
            self._client.unsubscribe(self.id)
        self._end()

    def _keep(self, frame: Frame) -> None:
        if len(self._frames) == self._frames.maxlen:
            self.dropped += 1
        self._frames.append(frame)

    def _end(self) -> None:
        self.active = False
        self._frames.clear()


class Client:
    """A connection to a Nephele daemon's socket protocol.

    `timeout` (seconds, None for no limit) bounds each request, from sending it to the last
    byte of its reply, and each wait for a subscribed frame; it may be changed at any time. When
    it runs out, RequestTimeout is raised and the connection is closed, since the late reply
    could still come and be taken for the next one's. A lost connection raises ConnectionError
    (an OSError) and is closed too. `reconnect()` then opens a new connection and sends `hello`
    with the token again. Nothing is repeated on its own: a request whose reply was lost may or
    may not have been carried out, and subscriptions end with their connection.

    `token` is sent with `hello` on every connection, for a daemon configured with one.
    `connect_timeout` bounds opening a connection; `queued_frames` is how many unread frames
    each subscription keeps (Subscription). Arguments may be numpy arrays and scalars; NaN and
    infinity, which strict JSON cannot hold, raise ValueError with nothing sent.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, *,
                 token: str | None = None, timeout: float | None = 60.0,
                 connect_timeout: float | None = 10.0, queued_frames: int = 16) -> None:
        self.host = host
        self.port = port
        self.token = token
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self.queued_frames = queued_frames
        self._connection: Connection | None = None
        self._next_id = 1
        self._subscriptions: dict[int, Subscription] = {}
        self._unclaimed: list[Frame] | None = None  # frames that came before their subscribe reply
        self.reconnect()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    @property
    def connected(self) -> bool:
        return self._connection is not None

    def reconnect(self) -> None:
        """Closes the connection if open, opens a new one and sends `hello` with the token."""
        self.close()
        self._connection = Connection(self.host, self.port, self.connect_timeout)
        if self.token is not None:
            self.hello(token=self.token)

    def close(self) -> None:
        """Closes the connection; its subscriptions end with it."""
        if self._connection is not None:
            self._connection.close()
            self._connection = None
        for subscription in self._subscriptions.values():
            subscription._end()
        self._subscriptions.clear()

    # ---- Commands, in the order of protocol/commands.inc ----

    def hello(self, token: str | None = None) -> JsonObject:
        """`hello`: the server, version, protocol, views, mode and tick_rate. With a token
        configured in the daemon, `token` must be sent before any other command."""
        return self._call("hello", token=token)

    def get_view(self, view: str | None = None) -> JsonObject:
        """`get_view`: the view named `view`, or every view as `views`."""
        return self._call("get_view", view=view)

    def set_view(self, view: str, position: Sequence[float] | None = None,
                 heading: float | None = None, pitch: float | None = None,
                 roll: float | None = None, vfov: float | None = None, width: int | None = None,
                 height: int | None = None, frustum: Mapping[str, float] | None = None,
                 format: str | None = None, channels: Sequence[str] | None = None) -> JsonObject:
        """`set_view`: changes a view; the result is the view after the change.

        position [x, y, z] m (z >= 0); heading, pitch (-90 to 90), roll degrees; vfov degrees;
        width, height pixels (1 to 16384). frustum {left, right, bottom, top} degrees (-89 to
        89) makes an off-axis view (then vfov is top - bottom and width follows the height); a
        later vfov centres it again. format "raw", "png", "jpeg" or "exr" and channels (see
        `render`) are what a render of the view gives without its own.
        """
        return self._call("set_view", view=view, position=position, heading=heading,
                          pitch=pitch, roll=roll, vfov=vfov, width=width, height=height,
                          frustum=frustum, format=format, channels=channels)

    def set_weather(self, layer: int, type: int, base: float | None = None,
                    thickness: float | None = None, coverage: float | None = None,
                    wind: Sequence[float] | None = None, visibility: float | None = None,
                    transition_band: float | None = None, scud: float | None = None,
                    precipitation: str | None = None, precipitation_rate: float | None = None,
                    precipitation_visibility: float | None = None,
                    centre: Sequence[float] | None = None, size: Sequence[float] | None = None,
                    heading: float | None = None, edge: float | None = None,
                    front: str | None = None, transition: float | None = None,
                    spacing: float | None = None, variation: float | None = None) -> JsonObject:
        """`set_weather`: sets a weather layer; the result is layer, type (by name, as
        "stratus") and the world's counts of layers, clouds and fields.

        layer 1-3 are cloud layers, 4-9 CIGI's precipitation layers (rain, snow, sleet, hail,
        sand, dust; type 0 only). type is CIGI's cloud type: 0 none (removes the layer),
        1 altocumulus, 2 altostratus, 3 cirrocumulus, 4 cirrostratus, 5 cirrus,
        6 cumulonimbus, 7 cumulus, 8 nimbostratus, 9 stratocumulus, 10 stratus.
        base, thickness m; coverage % (0 removes the layer); wind [east, north] m/s at the
        layer's middle height; visibility m inside a stratiform layer (1 to 1e7; 0: the
        genus's); transition_band m (0 to 1e4); scud % (0 to 100).
        precipitation "none", "rain", "snow", "sleet", "hail", "sand" or "dust";
        precipitation_rate mm/h (0 to 500); precipitation_visibility m (1 to 1e6; 0: the
        rate's; sand and dust need one).
        A macrocluster or one side of a front: centre [east, north] m, size [across, along] m
        (1 to 2e7; without it the layer is unbounded), heading degrees, edge m, front "left" or
        "right", transition m (0 to 1e7, with front only), spacing m and variation 0-1 (heaps).
        """
        return self._call("set_weather", layer=layer, type=type, base=base, thickness=thickness,
                          coverage=coverage, wind=wind, visibility=visibility,
                          transition_band=transition_band, scud=scud,
                          precipitation=precipitation, precipitation_rate=precipitation_rate,
                          precipitation_visibility=precipitation_visibility, centre=centre,
                          size=size, heading=heading, edge=edge, front=front,
                          transition=transition, spacing=spacing, variation=variation)

    def set_wind(self, velocity: Sequence[float]) -> JsonObject:
        """`set_wind`: the same wind, [east, north] m/s, at every altitude (and the sea's)."""
        return self._call("set_wind", velocity=velocity)

    def set_sun(self, azimuth: float | None = None, elevation: float | None = None,
                utc: str | None = None) -> JsonObject:
        """`set_sun`: the sun by azimuth and elevation (degrees), or by utc
        "YYYY-MM-DDTHH:MM[:SS[.fff]]" then "Z" or "+HH:MM"/"-HH:MM" (years 1901-2099), placed
        by its solar coordinates at the site. The result is azimuth, elevation (and utc)."""
        return self._call("set_sun", azimuth=azimuth, elevation=elevation, utc=utc)

    def set_fog(self, enabled: bool | None = None, top: float | None = None,
                visibility: float | None = None,
                colour: Sequence[float] | None = None) -> JsonObject:
        """`set_fog`: ground fog from the ground to top m (0 to 1e5), visibility m (1 to 1e7),
        colour [r, g, b]; enabled=False removes it. Unset fields keep their values; with none
        the fog is only read back. The result is enabled, top, visibility, colour."""
        return self._call("set_fog", enabled=enabled, top=top, visibility=visibility,
                          colour=colour)

    def set_haze(self, enabled: bool | None = None, visibility: float | None = None,
                 scale_height: float | None = None) -> JsonObject:
        """`set_haze`: distance haze, visibility m (10 to 1e7) thinning with height over
        scale_height m (10 to 1e5); enabled=False removes it. Unset fields keep their values
        (a first haze starts from 40,000 m and 1,200 m); with none the haze is only read
        back."""
        return self._call("set_haze", enabled=enabled, visibility=visibility,
                          scale_height=scale_height)

    def set_sea(self, enabled: bool | None = None, fetch: float | None = None,
                temperature: float | None = None, clarity: float | None = None,
                whitecaps: bool | None = None, seed: int | None = None,
                waves: Sequence[Mapping[str, Any]] | None = None) -> JsonObject:
        """`set_sea`: the sea in place of the ground plane; with no field it is read back.

        fetch m (0 to 2e6; 0: fully developed), temperature degrees C (-2 to 40), clarity 0
        (turbid) to 1 (clear), whitecaps, seed (0 to 2^63 - 1); enabled=False removes the sea.
        waves: 1 to 8 trains, each {id 0-255, and optionally enabled (False removes it), height
        m trough to crest 0-30, wavelength m 1-2000, period s 0-60 (0: deep-water dispersion),
        direction degrees (where it travels towards, clockwise from north), phase degrees}.
        Unset fields and trains not named keep their values. The result is enabled and, with a
        sea, wind, fetch, temperature, clarity, whitecaps, seed and waves.
        """
        return self._call("set_sea", enabled=enabled, fetch=fetch, temperature=temperature,
                          clarity=clarity, whitecaps=whitecaps, seed=seed, waves=waves)

    def set_site(self, latitude: float | None = None, longitude: float | None = None,
                 grid: float | None = None) -> JsonObject:
        """`set_site`: where the database lies on the Earth, latitude and longitude in degrees
        (given together), with grid the database's north at the site in degrees clockwise from
        true north (by default the one that keeps the content's axes). With no fields the
        database origin is only read back."""
        return self._call("set_site", latitude=latitude, longitude=longitude, grid=grid)

    def set_time(self, time_scale: float | None = None, paused: bool | None = None,
                 advance: float | None = None, mode: str | None = None) -> JsonObject:
        """`set_time`: time_scale 0-1000 simulated seconds per second, paused, advance s
        (0 to 1e7) at once, mode "realtime" or "lockstep". The result is time, time_scale,
        paused, mode, ticks."""
        return self._call("set_time", time_scale=time_scale, paused=paused, advance=advance,
                          mode=mode)

    def add_cloud(self, cloud: Mapping[str, Any]) -> JsonObject:
        """`add_cloud`: cloud holds the keys of a scene file's [[cloud]] table, `name`
        required and unique. The result is name and ellipsoids."""
        return self._call("add_cloud", cloud=cloud)

    def change_cloud(self, name: str, move: Sequence[float] | None = None,
                     threshold: float | None = None, limb_threshold: float | None = None,
                     transition: float | None = None,
                     colour: Sequence[float] | None = None) -> JsonObject:
        """`change_cloud`: moves a cloud by move [dx, dy, dz] m, or changes its threshold,
        limb_threshold, transition or colour [r, g, b]."""
        return self._call("change_cloud", name=name, move=move, threshold=threshold,
                          limb_threshold=limb_threshold, transition=transition, colour=colour)

    def remove_cloud(self, name: str) -> JsonObject:
        """`remove_cloud`: removes the cloud named `name`."""
        return self._call("remove_cloud", name=name)

    def add_target(self, target: Mapping[str, Any]) -> JsonObject:
        """`add_target`: target holds the keys of a scene file's [[target]] (name required and
        unique, shape "box"/"ellipsoid", centre, heading, pitch, roll, size, colour), or `type`
        naming a config [[entity_type]]. The result is the target with its object_id."""
        return self._call("add_target", target=target)

    def move_target(self, name: str, centre: Sequence[float] | None = None,
                    heading: float | None = None, pitch: float | None = None,
                    roll: float | None = None) -> JsonObject:
        """`move_target`: the target after the move."""
        return self._call("move_target", name=name, centre=centre, heading=heading,
                          pitch=pitch, roll=roll)

    def remove_target(self, name: str) -> JsonObject:
        """`remove_target`: removes the target named `name`."""
        return self._call("remove_target", name=name)

    def list_targets(self) -> JsonObject:
        """`list_targets`: `targets`, each with name, shape, centre, attitude, size and
        object_id (its value in the object_id channel)."""
        return self._call("list_targets")

    def tick(self, dt: float) -> JsonObject:
        """`tick`: advances a lockstep world by dt s (0 to 3600); the result is time, ticks.
        Refused (`failed`) in realtime mode."""
        return self._call("tick", dt=dt)

    @overload
    def render(self, view: str, *, camera: Mapping[str, Any] | None = None,
               format: str | None = None, channels: Sequence[str] | None = None) -> Frame: ...

    @overload
    def render(self, *, views: Sequence[str], format: str | None = None,
               channels: Sequence[str] | None = None) -> list[Frame]: ...

    def render(self, view: str | None = None, views: Sequence[str] | None = None,
               camera: Mapping[str, Any] | None = None, format: str | None = None,
               channels: Sequence[str] | None = None) -> Frame | list[Frame]:
        """`render`: one Frame of `view`, or a list of Frames of `views` (1 to 16 names), all
        of the same tick.

        format "raw", "png", "jpeg" or "exr"; channels a list of "colour", "coverage", and with
        raw or exr the ground-truth channels "depth", "cloud_depth", "object_id",
        "visibility", "lwir", "glint" (Frame says their dtypes and units). Without them the
        view's own format and channels are used. camera (one view only) sets position,
        heading, pitch, roll, vfov, width, height for this render alone.
        """
        frames = [_rendered_frame(message, data)
                  for message, data in self._exchange("render", view=view, views=views,
                                                       camera=camera, format=format,
                                                       channels=channels)]
        return frames if views is not None else frames[0]

    def subscribe(self, view: str, rate: float | None = None, format: str | None = None,
                  channels: Sequence[str] | None = None) -> Subscription:
        """`subscribe`: frames of `view` as they are rendered, as an iterable Subscription.

        rate Hz (0.01 to 60) in realtime mode; in lockstep mode one frame per tick. Both send
        one frame at once. format and channels as for `render`.
        """
        self._unclaimed = []
        try:
            reply = self._call("subscribe", view=view, rate=rate, format=format,
                               channels=channels)
            subscription = Subscription(self, reply["subscription"], reply, self.queued_frames)
            self._subscriptions[subscription.id] = subscription
            for frame in self._unclaimed:
                if frame.subscription == subscription.id:
                    subscription._keep(frame)
        finally:
            self._unclaimed = None
        return subscription

    def unsubscribe(self, subscription: int) -> JsonObject:
        """`unsubscribe`: ends the subscription with id `subscription`; its iteration ends."""
        result = self._call("unsubscribe", subscription=subscription)
        if (ended := self._subscriptions.pop(subscription, None)) is not None:
            ended._end()
        return result

    def stream(self, view: str, address: str, bitrate: int | None = None,
               rate: float | None = None, keyframe_interval: int | None = None,
               encoder: str | None = None, stamp: bool | None = None) -> JsonObject:
        """`stream`: the view as live H.264 to `address` (udp://host:port MPEG-TS,
        srt://host:port, or rtp://host:port with the result's `sdp`), bitrate 100-100000 kbit/s
        (4000), rate 0.5-60 Hz (30), keyframe_interval 1-600 frames (30), encoder "auto",
        "libx264" or "h264_nvenc", stamp: each frame's tick in its top-left corner. Frames
        follow the world's ticks as a subscription's do, until `unstream`. The result is
        stream (its id), view, address, encoder, width, height, rate, bitrate,
        keyframe_interval and, for RTP, sdp."""
        return self._call("stream", view=view, address=address, bitrate=bitrate, rate=rate,
                          keyframe_interval=keyframe_interval, encoder=encoder, stamp=stamp)

    def unstream(self, stream: int) -> JsonObject:
        """`unstream`: ends the streamed view with id `stream`; the result is stream, sent and
        dropped (frames)."""
        return self._call("unstream", stream=stream)

    def snapshot(self, name: str) -> JsonObject:
        """`snapshot`: saves the world as `name`.snap in the daemon's snapshot directory; the
        result is name, time, hash."""
        return self._call("snapshot", name=name)

    def restore(self, name: str) -> JsonObject:
        """`restore`: brings back the snapshot `name`; the result is name, time, hash."""
        return self._call("restore", name=name)

    def stats(self) -> JsonObject:
        """`stats`: the daemon's counters and the last frame's costs (PROTOCOL.md, "Stats")."""
        return self._call("stats")

    def hash(self) -> JsonObject:
        """`hash`: the world's hash (16 hex digits), time, time_ns, ticks."""
        return self._call("hash")

    # ---- The exchange of messages ----

    def _call(self, cmd: str, **fields: Any) -> JsonObject:
        message, _ = self._exchange(cmd, **fields)[0]
        result: JsonObject = message["result"]
        return result

    def _exchange(self, cmd: str, **fields: Any) -> list[tuple[JsonObject, bytearray | None]]:
        """Sends one request and returns its reply: one message, or one per part of a render
        of several views. Frames that come meanwhile are queued for their subscriptions."""
        connection = self._open_connection()
        request_id = self._next_id
        self._next_id += 1
        request = {"id": request_id, "cmd": cmd}
        request.update((key, value) for key, value in fields.items() if value is not None)
        line = request_line(request)  # a field JSON cannot hold fails here, with nothing sent
        deadline = deadline_after(self.timeout)
        replies: list[tuple[JsonObject, bytearray | None]] = []
        try:
            connection.send(line, deadline)
            while True:
                message, data = connection.receive(deadline)
                if "event" in message:
                    self._keep_event(message, data)
                    continue
                # A line the daemon could not read at all is answered with a null id.
                if message.get("id") not in (request_id, None):
                    raise ConnectionError(f"a reply to request {message.get('id')} came while "
                                          f"request {request_id} waited")
                if not message["ok"]:
                    raise NepheleError(message["error"]["code"], message["error"]["message"])
                replies.append((message, data))
                image = image_header(message)
                if image is None or len(replies) == image.get("parts", 1):
                    return replies
        except (OSError, ValueError):
            self.close()
            raise

    def _wait_for_frame(self, subscription: Subscription) -> None:
        """Reads until a frame of `subscription` is queued, within the client's timeout."""
        connection = self._open_connection()
        deadline = deadline_after(self.timeout)
        try:
            while subscription.active and not subscription._frames:
                message, data = connection.receive(deadline)
                if "event" not in message:
                    raise ConnectionError(f"a reply to request {message.get('id')} came while "
                                          "no request waited")
                self._keep_event(message, data)
        except (OSError, ValueError):
            self.close()
            raise

    def _keep_event(self, message: JsonObject, data: bytearray | None) -> None:
        """Queues a frame event for its subscription; other events, and frames of ended
        subscriptions, are dropped."""
        if message["event"] != "frame" or data is None:
            return
        frame = Frame(message["image"], data, message["subscription"])
        if (subscription := self._subscriptions.get(message["subscription"])) is not None:
            subscription._keep(frame)
        elif self._unclaimed is not None:
            self._unclaimed.append(frame)

    def _open_connection(self) -> Connection:
        if self._connection is None:
            raise ConnectionError("the client is not connected: call reconnect()")
        return self._connection
