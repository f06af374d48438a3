"""What a car archive's file is called: `.tar.gz` (or `.tgz`), as the car's upload page wants.
Apart from the archive reader so the app can tell the names without loading it."""

from __future__ import annotations

from pathlib import Path

CAR_ARCHIVE_SUFFIX = ".tar.gz"
CAR_ARCHIVE_SUFFIXES = (CAR_ARCHIVE_SUFFIX, ".tgz")


def is_car_archive_name(path: Path) -> bool:
    """Whether the file's name says it is a car archive."""
    return path.name.endswith(CAR_ARCHIVE_SUFFIXES)


def car_archive_path(out: Path) -> Path:
    """`out`, with `.tar.gz` added if it lacks it."""
    out = Path(out).expanduser()
    return out if is_car_archive_name(out) else out.with_name(out.name + CAR_ARCHIVE_SUFFIX)
