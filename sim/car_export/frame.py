"""A picture prepared as a physical DeepRacer prepares its camera frames.

The car's inference node (aws-deepracer-inference-pkg `image_process.cpp`) resizes each
camera image with OpenCV's `cv::resize` (bilinear, INTER_LINEAR) to the model's 160x120 and
converts it with `cv::COLOR_BGR2GRAY`; the graph gets those 0..255 values as float32, with
no normalisation and no frame stacking. This module does the same without OpenCV: Pillow
only decodes the file, and the resize and grey conversion follow OpenCV's definitions
(pixel centres at half-pixel offsets, no anti-aliasing; Y = 0.299 R + 0.587 G + 0.114 B),
each rounded to 8 bits as OpenCV does. OpenCV computes in fixed point, so a pixel may
differ from the car's by one grey level.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sim.car_archive.errors import CarModelError

FRAME_WIDTH = 160
FRAME_HEIGHT = 120
# A phone photo is about 12-50 megapixels; refuse anything that could not be one (Pillow's
# own decompression-bomb limit, about 89 megapixels, stops larger ones when it opens them).
MAX_PIXELS = 80_000_000
GREY_WEIGHTS = np.array([0.299, 0.587, 0.114])  # OpenCV's RGB-to-grey (ITU-R BT.601)


def read_picture(path: Path) -> NDArray[np.uint8]:
    """The picture at `path` as (H, W, 3) RGB uint8; one sentence when it cannot be read."""
    from PIL import Image, UnidentifiedImageError  # noqa: PLC0415 (Pillow: only when a picture is read)

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                if image.width * image.height > MAX_PIXELS:
                    raise CarModelError(
                        f"{path}: the picture is {image.width}x{image.height}, more than "
                        f"{MAX_PIXELS:,} pixels; give a camera picture."
                    )
                return np.asarray(image.convert("RGB"), dtype=np.uint8)
    except FileNotFoundError:
        raise CarModelError(f"{path}: the file does not exist.") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise CarModelError(
            f"{path}: the picture has more than {MAX_PIXELS:,} pixels; give a camera picture."
        ) from None
    except UnidentifiedImageError:
        raise CarModelError(
            f"{path}: not a picture racer-tui can read; give a PNG or JPEG camera picture."
        ) from None
    except OSError as error:
        raise CarModelError(f"{path}: cannot read it ({error}).") from None


def car_frame(
    rgb: NDArray[np.uint8], width: int = FRAME_WIDTH, height: int = FRAME_HEIGHT
) -> NDArray[np.uint8]:
    """`rgb` (H, W, 3) resized bilinearly to width x height and greyed, as the car does."""
    resized = np.clip(np.rint(_resize_bilinear(np.asarray(rgb), width, height)), 0, 255)
    grey = resized @ GREY_WEIGHTS
    return np.asarray(np.clip(np.rint(grey), 0, 255), dtype=np.uint8)


def _resize_bilinear(image: NDArray[np.uint8], width: int, height: int) -> NDArray[np.float64]:
    """Only the source pixels the output reads are taken (in 8 bits) before any arithmetic:
    a 48-megapixel photo costs a few megabytes, not gigabytes."""
    top_row, bottom_row, row_weight = _taps(image.shape[0], height)
    left, right, weight = _taps(image.shape[1], width)
    rows = row_weight[:, None, None]
    cols = weight[None, :, None]

    def blend(source_rows: NDArray[np.intp]) -> NDArray[np.float64]:
        picked = image[source_rows]  # (height, W, 3), still uint8
        near = picked[:, left].astype(np.float64)
        far = picked[:, right].astype(np.float64)
        out: NDArray[np.float64] = near * cols + far * (1 - cols)
        return out

    out: NDArray[np.float64] = blend(top_row) * rows + blend(bottom_row) * (1 - rows)
    return out


def _taps(size: int, out: int) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """For each output pixel: the two source pixels and the first one's weight (OpenCV's
    INTER_LINEAR: centres aligned, the source position clamped to the image)."""
    position = (np.arange(out) + 0.5) * (size / out) - 0.5
    position = np.clip(position, 0, size - 1)
    low = np.floor(position).astype(np.intp)
    high = np.minimum(low + 1, size - 1)
    return low, high, 1.0 - (position - low)
