"""Fixtures for car archives: the real DeepRacer-trained model in ../shared (skips when
absent) and its demo frame as DeepRacer's runtime was fed it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim.car_archive.archive import CarArchive, read_car_archive
from tests.conftest import SHARED_DEEPRACER


@pytest.fixture(scope="module")
def sample_archive_path() -> Path:
    path = SHARED_DEEPRACER / "car-model" / "sample-model.tar.gz"
    if not path.is_file():
        pytest.skip("../shared/deepracer/car-model is not beside this checkout")
    return path


@pytest.fixture(scope="module")
def sample_archive(sample_archive_path: Path) -> CarArchive:
    return read_car_archive(sample_archive_path)


@pytest.fixture(scope="module")
def demo_frame(sample_archive_path: Path) -> np.ndarray:
    """dr-demo-1.png as the shared README prepares it: 160x120 bicubic (Pillow), greyed as
    0.2989 R + 0.5870 G + 0.1140 B, raw 0..255, (1, 120, 160) float64."""
    image_module = pytest.importorskip("PIL.Image")
    with image_module.open(sample_archive_path.parent / "dr-demo-1.png") as image:
        small = image.convert("RGB").resize((160, 120), image_module.Resampling.BICUBIC)
    rgb = np.asarray(small, dtype=np.float64)
    return (rgb @ np.array([0.2989, 0.5870, 0.1140]))[np.newaxis]
