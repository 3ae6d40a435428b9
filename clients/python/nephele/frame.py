"""Image replies and subscribed frames as numpy arrays (PROTOCOL.md, "Images")."""
from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from PIL import Image

JsonObject = dict[str, Any]
Array = NDArray[Any]

# The channels of 8-bit raw images: interleaved, colour (sRGB) before coverage (linear).
_BYTE_CHANNELS = {"colour": 3, "coverage": 1}


@dataclass(frozen=True)
class Camera:
    """The pose and pinhole intrinsics a frame was rendered with, as its header's `camera`.

    Positions in metres in the world frame (X east, Y north, Z up), angles in degrees.
    `focal_px` is (height / 2) / tan(vfov / 2); `principal_point` is in pixels from the
    top-left corner. `frustum` (left, right, bottom, top in degrees) is set for off-axis views.
    """

    position: tuple[float, float, float]
    heading_deg: float
    pitch_deg: float
    roll_deg: float
    vfov_deg: float
    focal_px: float
    principal_point: tuple[float, float]
    frustum: dict[str, float] | None

    @staticmethod
    def from_header(camera: JsonObject) -> Camera:
        x, y, z = camera["position"]
        cx, cy = camera["principal_point"]
        return Camera((x, y, z), camera["heading_deg"], camera["pitch_deg"], camera["roll_deg"],
                      camera["vfov_deg"], camera["focal_px"], (cx, cy), camera.get("frustum"))


class Frame:
    """One image from the daemon: a `render` reply or a subscribed frame.

    `header` is the image header as sent; `data` the bytes that followed it. The header's
    fields are also attributes: `view`, `width`, `height`, `format`, `encoding`, `time`
    (simulated seconds), `tick`, `frame` (the daemon's frame counter) and `camera` (a Camera).
    `subscription` is the subscription id of a subscribed frame, None for a render reply.

    A raw image is also split into numpy arrays, one per channel, in `channels` (and
    `frame[name]`), in the header's order. They are views of `data`, rows top-down:

    - 8-bit raw (colour and coverage only, `encoding` "srgb"): `colour` uint8 (height, width,
      3), sRGB-encoded; `coverage` uint8 (height, width), the clouds' opacity, linear, 255 for
      opaque.
    - float32 planes (any ground-truth channel, `encoding` "float32-planes"): `colour` float32
      (height, width, 3), linear RGB; `coverage` float32 0-1; `depth` metres to the first
      opaque surface (inf: sky); `cloud_depth` metres to where the cloud opacity reaches 1/2
      (inf: never); `object_id` 1 + the index of the target seen (0: none, -1: the sea), as a
      float32; `visibility` the clouds' transmittance 0-1; `lwir` long-wave infrared radiance,
      W m^-2 sr^-1; `glint` the sun's glint on the sea, in colour's units. Each is float32
      (height, width).

    PNG, JPEG and EXR images stay encoded in `data` and `channels` is empty; `to_pil()` opens
    PNG and JPEG.
    """

    def __init__(self, header: JsonObject, data: bytearray, subscription: int | None) -> None:
        self.header = header
        self.data = data
        self.subscription = subscription
        self.view: str = header["view"]
        self.width: int = header["width"]
        self.height: int = header["height"]
        self.format: str = header["format"]
        self.encoding: str = header["encoding"]
        self.time: float = header["time"]
        self.tick: int = header["tick"]
        self.frame: int = header["frame"]
        self.camera = Camera.from_header(header["camera"])
        self.channels: dict[str, Array] = self._split() if self.format == "raw" else {}

    def __getitem__(self, channel: str) -> Array:
        if channel not in self.channels:
            raise KeyError(f"{channel!r}: this frame holds {self._holds()}")
        return self.channels[channel]

    def __repr__(self) -> str:
        return (f"Frame(view={self.view!r}, {self.width}x{self.height}, format={self.format!r}, "
                f"channels={self.header['channels']}, tick={self.tick}, time={self.time})")

    def to_pil(self, channel: str = "colour") -> Image.Image:
        """The frame as a PIL image, for a notebook or a file (needs Pillow).

        `colour` is RGB, 8-bit sRGB (linear float colour is sRGB-encoded and clipped to 0-1);
        any other channel of a raw image is grey, its finite values stretched to 0-255. PNG and
        JPEG images are opened as they are (`channel` must be "colour"); EXR is refused.
        """
        from PIL import Image  # optional: only this method needs Pillow

        if self.format in ("png", "jpeg"):
            if channel != "colour":
                raise ValueError(f"{channel!r}: a {self.format} image holds colour only")
            return Image.open(io.BytesIO(self.data)).convert("RGB")
        pixels = self[channel]
        if pixels.dtype == np.uint8:
            return Image.fromarray(np.ascontiguousarray(pixels))
        if channel == "colour":
            return Image.fromarray(_srgb8(pixels))
        return Image.fromarray(_stretched8(pixels))

    def _repr_png_(self) -> bytes | None:
        """Jupyter's inline display: the colour as PNG (None when there is nothing to show)."""
        if self.format == "png":
            return bytes(self.data)
        if "colour" not in self.channels and self.format != "jpeg":
            return None
        try:
            image = self.to_pil()
        except ImportError:  # no Pillow: the notebook shows repr() instead
            return None
        out = io.BytesIO()
        image.save(out, format="PNG")
        return out.getvalue()

    def _holds(self) -> str:
        if self.format != "raw":
            return (f"a {self.format} file in frame.data (format raw gives arrays; to_pil() "
                    "opens png and jpeg)")
        return "channels " + ", ".join(self.channels)

    def _split(self) -> dict[str, Array]:
        names: list[str] = self.header["channels"]
        if self.encoding == "float32-planes":
            return self._split_planes(names)
        return self._split_bytes(names)

    def _split_planes(self, names: list[str]) -> dict[str, Array]:
        """Float32 planes, little-endian, one per channel in the order of `names` (colour: 3)."""
        plane_count = sum(3 if name == "colour" else 1 for name in names)
        planes = self._pixels(np.dtype("<f4"), plane_count).reshape(
            plane_count, self.height, self.width)
        out: dict[str, Array] = {}
        first = 0
        for name in names:
            if name == "colour":
                out[name] = np.ascontiguousarray(np.moveaxis(planes[first:first + 3], 0, -1))
                first += 3
            else:
                out[name] = planes[first]
                first += 1
        return out

    def _split_bytes(self, names: list[str]) -> dict[str, Array]:
        """8-bit pixels, interleaved: colour's R, G, B first, then coverage, whatever the order
        of `names`."""
        stride = sum(_BYTE_CHANNELS[name] for name in names)
        pixels = self._pixels(np.dtype(np.uint8), stride).reshape(self.height, self.width, stride)
        out: dict[str, Array] = {}
        if "colour" in names:
            out["colour"] = pixels[:, :, :3]
        if "coverage" in names:
            out["coverage"] = pixels[:, :, stride - 1]
        return {name: out[name] for name in names}

    def _pixels(self, dtype: np.dtype[Any], per_pixel: int) -> Array:
        expected = self.width * self.height * per_pixel * dtype.itemsize
        if len(self.data) != expected:
            raise ValueError(f"image of {len(self.data)} bytes; its header "
                             f"({self.width}x{self.height}, {self.header['channels']}) "
                             f"means {expected}")
        return np.frombuffer(self.data, dtype=dtype)


def _srgb8(linear: Array) -> Array:
    """Linear RGB to 8-bit sRGB (IEC 61966-2-1), clipped to 0-1 first."""
    c = np.clip(np.nan_to_num(linear), 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    srgb: Array = np.round(encoded * 255.0).astype(np.uint8)
    return srgb


def _stretched8(plane: Array) -> Array:
    """A float plane as grey levels: its finite range onto 0-255, infinity white, NaN black."""
    finite = np.isfinite(plane)
    grey = np.where(np.isposinf(plane), 255.0, 0.0)
    if finite.any():
        low, high = float(plane[finite].min()), float(plane[finite].max())
        grey[finite] = (plane[finite] - low) * (255.0 / (high - low) if high > low else 0.0)
    levels: Array = np.round(grey).astype(np.uint8)
    return levels
