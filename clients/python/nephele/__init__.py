"""A client for Nephele's socket protocol (protocol/PROTOCOL.md in the Nephele repository).

    import nephele
    with nephele.Client("127.0.0.1", 7600) as client:
        client.set_weather(layer=1, type=7, base=1200, thickness=800, coverage=40)
        frame = client.render("front", format="raw", channels=["colour", "depth"])
        colour, depth = frame["colour"], frame["depth"]

`Client` has one method per command; `render` returns `Frame`s, whose channels are numpy
arrays; `subscribe` returns a `Subscription`, an iterator of frames. The daemon's error replies
are raised as `NepheleError`; a wait past the client's timeout as `RequestTimeout`.
`LocalDaemon` starts `nephele serve` on this machine; `nephele.cigi` drives the daemon as a
CIGI 3.3 host.
"""
from .client import DEFAULT_PORT, Client, Subscription
from .daemon import LocalDaemon
from .errors import NepheleError, RequestTimeout
from .frame import Camera, Frame

__all__ = ["DEFAULT_PORT", "Camera", "Client", "Frame", "LocalDaemon", "NepheleError",
           "RequestTimeout", "Subscription"]
__version__ = "0.1.0"
