"""Validation of camera images given to the vision cores (shape, dtype, size)."""

from __future__ import annotations

import cv2
import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["to_gray"]


def to_gray(image: np.ndarray, width: int, height: int, name: str = "image") -> np.ndarray:
    """Validate an 8-bit image of the expected size and return it as (H, W) uint8 grey.

    Args:
        image: (H, W) uint8 grey or (H, W, 3) uint8 RGB image.
        width: expected width W [px].
        height: expected height H [px].
        name: the argument's name, for the error message.

    Raises:
        InvalidInput: wrong type, dtype, number of channels or size.
    """
    if not isinstance(image, np.ndarray):
        raise InvalidInput(f"{name}: expected a numpy array, got {type(image).__name__}")
    if image.dtype != np.uint8:
        raise InvalidInput(f"{name}: expected dtype uint8, got {image.dtype}")
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 2:
        gray = image
    elif image.ndim == 3 and image.shape[2] == 3:
        gray = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2GRAY)
    else:
        raise InvalidInput(
            f"{name}: expected shape (H, W) grey or (H, W, 3) RGB, got {image.shape}"
        )
    if gray.shape != (height, width):
        raise InvalidInput(
            f"{name}: expected {width}x{height} (W x H), got {gray.shape[1]}x{gray.shape[0]}"
        )
    return np.ascontiguousarray(gray)
