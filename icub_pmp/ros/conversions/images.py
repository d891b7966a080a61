"""sensor_msgs/Image <-> numpy uint8 arrays (rgb8, bgr8, mono8)."""

from __future__ import annotations

import numpy as np
from builtin_interfaces.msg import Time
from sensor_msgs.msg import Image

from icub_pmp.errors import InvalidInput, UnknownName

__all__ = ["image_to_array", "array_to_image", "IMAGE_ENCODINGS"]


#: encodings image_to_array accepts -> channels (bgr8 is returned as RGB).
IMAGE_ENCODINGS = {"rgb8": 3, "bgr8": 3, "mono8": 1}


def image_to_array(
    msg: Image, width: int | None = None, height: int | None = None
) -> np.ndarray:
    """sensor_msgs/Image (rgb8, bgr8, mono8) -> (H, W, 3) RGB or (H, W) grey uint8 array.

    Checks the encoding, the optional expected size [px], ``step`` and the data length;
    raises :class:`InvalidInput` naming what is wrong. The array is a copy.
    """
    enc = msg.encoding.lower()
    if enc not in IMAGE_ENCODINGS:
        raise UnknownName("image encoding", msg.encoding, IMAGE_ENCODINGS)
    h, w, ch = int(msg.height), int(msg.width), IMAGE_ENCODINGS[enc]
    if (width is not None and w != width) or (height is not None and h != height):
        raise InvalidInput(f"image size {w}x{h} (W x H); expected {width}x{height}")
    if h <= 0 or w <= 0:
        raise InvalidInput(f"image size {w}x{h} is empty")
    step = int(msg.step)
    if step < w * ch:
        raise InvalidInput(f"image step {step} < width * channels = {w * ch}")
    data = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if data.size != step * h:
        raise InvalidInput(f"image data has {data.size} bytes; step * height = {step * h}")
    rows = data.reshape(h, step)[:, : w * ch]
    if ch == 1:
        return rows.copy()
    a = rows.reshape(h, w, 3)
    return (a[:, :, ::-1] if enc == "bgr8" else a).copy()


def array_to_image(
    a: np.ndarray, encoding: str = "mono8", stamp: Time | None = None, frame_id: str = ""
) -> Image:
    """(H, W) uint8 -> mono8 or (H, W, 3) uint8 RGB -> rgb8 sensor_msgs/Image (data as bytes)."""
    a = np.ascontiguousarray(a)
    ch = IMAGE_ENCODINGS.get(encoding)
    if ch is None or encoding == "bgr8":
        raise UnknownName("image encoding", encoding, ("mono8", "rgb8"))
    if a.dtype != np.uint8 or a.ndim != (2 if ch == 1 else 3) or (ch == 3 and a.shape[2] != 3):
        shape = "(H, W)" if ch == 1 else "(H, W, 3)"
        raise InvalidInput(f"{encoding} image: expected uint8 {shape}, got {a.dtype} {a.shape}")
    msg = Image()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.height, msg.width = int(a.shape[0]), int(a.shape[1])
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = int(a.shape[1] * ch)
    msg.data = a.tobytes()
    return msg
