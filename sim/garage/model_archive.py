"""A model's `.tar.gz`, recognised by what it holds, never by its name alone.

Two kinds of model arrive as `.tar.gz`:
- a **car archive**: `model_metadata.json` and `agent/model.pb`, what a physical DeepRacer
  loads (racer-tui's car export, deepracer-for-cloud's car upload, DeepRacer on AWS's
  `physicalmodel-<name>.tar.gz`); `sim.car_archive.archive` reads it;
- a **DeepRacer on AWS virtual model** (`virtualmodel-<name>.tar.gz`, written by DRoA's
  `assetpackaging.ts`): the model's whole S3 folder as bare relative paths,
  `model_metadata.json`, `reward_function.py`, `training_params.yaml`, `ip/`, `model/`
  (rl_coach checkpoints and the frozen `model_<n>.pb` graphs), `metrics/{training,
  evaluation,submission}/<ISO time>-deepracerindy-<job>-<id>.json` and `logs/`.

A virtual model is unpacked into a scratch folder and imported as a DeepRacer folder
(`sim.garage.deepracer_import`). The archive comes from anyone, so only the files that
import reads or keeps are written out, each under its own size limit; everything else
(checkpoints, heartbeat files, nested archives) is skipped unread. Absolute names, `..`,
links and devices are refused; the entries, the bytes decompressed in all and the bytes
kept are capped before they can fill memory or disk.
"""

from __future__ import annotations

import gzip
import re
import shutil
import tarfile
import zlib
from enum import StrEnum
from pathlib import Path

from sim.car_archive.archive import GRAPH_MEMBER, MAX_GRAPH_BYTES
from sim.deepracer.files import (
    HYPERPARAMETERS_PATH,
    MAX_METADATA_BYTES,
    MAX_METRICS_BYTES,
    MAX_TRAINING_METRICS_BYTES,
    MODEL_METADATA,
    MODEL_METADATA_PATH,
    REWARD_FUNCTION,
    TRAINING_PARAMS,
)
from sim.foundation.untrusted_tar import CappedStream, Unsafe, UnsafeMemberError, member_name
from sim.garage.folder import ModelError

# DRoA lists at most 1,000 objects of a model when it packs one (one ListObjectsV2 call).
MAX_ENTRIES = 5_000
# DRoA imports a model folder of at most 1 GiB; that much may be written out here.
MAX_KEPT_BYTES = 1024**3
# Everything decompressed, kept or skipped (checkpoints are skipped but still unpacked).
MAX_UNPACKED_BYTES = 8 * 1024**3
MAX_LOG_BYTES = 256 * 1024**2
LOG_JOB_TYPES = ("training", "evaluation", "submission")
DROA_PREFIXES = ("virtualmodel-", "physicalmodel-")
ARCHIVE_SUFFIXES = (".tar.gz", ".tgz")

# What a virtual model's import reads or keeps, with each file's limit.
_KEPT_EXACT = {
    MODEL_METADATA: MAX_METADATA_BYTES,
    MODEL_METADATA_PATH: MAX_METADATA_BYTES,
    REWARD_FUNCTION: MAX_METADATA_BYTES,
    TRAINING_PARAMS: MAX_METADATA_BYTES,
    HYPERPARAMETERS_PATH: MAX_METADATA_BYTES,
    "model/deepracer_checkpoints.json": MAX_METADATA_BYTES,
}
_KEPT_PATTERNS = (
    (re.compile(r"model/model_\d+\.pb"), MAX_GRAPH_BYTES),
    (re.compile(r"metrics/training/[^/]+\.json"), MAX_TRAINING_METRICS_BYTES),
    (re.compile(r"metrics/(evaluation|submission)/[^/]+\.json"), MAX_METRICS_BYTES),
    (re.compile(rf"logs/({'|'.join(LOG_JOB_TYPES)})/[^/]+\.log"), MAX_LOG_BYTES),
)


class ArchiveKind(StrEnum):
    CAR = "car"
    VIRTUAL = "virtual"


def download_name(path: Path) -> str:
    """The model's name as DRoA's download names it: `virtualmodel-my-car.tar.gz` and
    `physicalmodel-my-car.tar.gz` are `my-car`; any other archive is its name without
    the suffix."""
    name = path.name
    for suffix in ARCHIVE_SUFFIXES:
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    for prefix in DROA_PREFIXES:
        if name.startswith(prefix) and len(name) > len(prefix):
            return name[len(prefix) :]
    return name


def unpack_model_archive(path: Path, into: Path) -> ArchiveKind:
    """Say which kind of model `path` holds; for a virtual model, write the files its
    import uses into the folder `into`. `ModelError` (one sentence naming the file) when
    it is neither kind, or breaks a limit, or is not a complete `.tar.gz`."""
    where = path.name
    seen: set[str] = set()
    kept_bytes = 0
    has_car_graph = False
    try:
        with path.open("rb") as raw, gzip.GzipFile(fileobj=raw) as unzipped:
            stream = CappedStream(unzipped, MAX_UNPACKED_BYTES, lambda: _unpacked_too_much(where))
            with tarfile.open(fileobj=stream, mode="r|") as tar:
                for count, member in enumerate(tar, start=1):
                    if count > MAX_ENTRIES:
                        raise ModelError(
                            f"{where} has more than {MAX_ENTRIES:,} entries, more than a "
                            "model's archive holds; give the archive as DeepRacer wrote it."
                        )
                    name = _checked_name(member, where)
                    if name is None:
                        continue
                    if name in seen:
                        raise ModelError(f"{where}: {name} appears twice in the archive.")
                    seen.add(name)
                    if name == GRAPH_MEMBER:
                        has_car_graph = True
                        break  # a car archive: its own reader takes it from here
                    limit = _limit(name)
                    if limit is None:
                        continue  # not used by the import: skipped unread
                    if member.size > limit:
                        raise ModelError(
                            f"{where}: {name} is {member.size:,} bytes, more than the "
                            f"{limit:,} such a file may have."
                        )
                    kept_bytes += member.size
                    if kept_bytes > MAX_KEPT_BYTES:
                        raise ModelError(
                            f"{where}: the files a model uses add up to more than "
                            f"{MAX_KEPT_BYTES:,} bytes, DeepRacer on AWS's own limit."
                        )
                    _write_member(tar, member, into / name, where)
    except ModelError:
        raise
    except (tarfile.TarError, EOFError, zlib.error, OSError):  # BadGzipFile is an OSError
        raise ModelError(
            f"{where} is not a complete gzip-compressed tar archive (truncated or corrupt); "
            "download it again."
        ) from None
    if has_car_graph:
        return ArchiveKind.CAR
    if MODEL_METADATA not in seen:
        raise ModelError(
            f"{where} holds no model: neither a car model (model_metadata.json with "
            f"{GRAPH_MEMBER}) nor a DeepRacer on AWS virtual model (model_metadata.json with "
            f"{REWARD_FUNCTION} and {TRAINING_PARAMS}); give a model archive as downloaded."
        )
    return ArchiveKind.VIRTUAL


# How far `may_hold_reward_code` reads before it answers "perhaps" (asking is harmless).
SCAN_BYTES = 256 * 1024**2


def may_hold_reward_code(path: Path) -> bool:
    """Whether the archive may bring a reward function someone wrote (a DeepRacer on AWS
    virtual model does; a car archive does not), read from its member names only, as far
    as `SCAN_BYTES` in: quick enough to ask before importing."""
    try:
        with path.open("rb") as raw, gzip.GzipFile(fileobj=raw) as unzipped:
            stream = CappedStream(unzipped, SCAN_BYTES, _scanned_enough)
            with tarfile.open(fileobj=stream, mode="r|") as tar:
                for member in tar:
                    name = member.name.removeprefix("./")
                    if name == GRAPH_MEMBER:
                        return False
                    if name == REWARD_FUNCTION:
                        return True
    except _ScannedEnoughError:
        return True
    except (tarfile.TarError, EOFError, zlib.error, OSError):
        return False  # not an archive at all: the import says what it is
    return False


class _ScannedEnoughError(Exception):
    pass


def _scanned_enough() -> None:
    raise _ScannedEnoughError


def _limit(name: str) -> int | None:
    if name in _KEPT_EXACT:
        return _KEPT_EXACT[name]
    for pattern, limit in _KEPT_PATTERNS:
        if pattern.fullmatch(name):
            return limit
    return None


def _checked_name(member: tarfile.TarInfo, where: str) -> str | None:
    """The member's name without a leading './', or None for a directory entry."""
    try:
        return member_name(member)
    except UnsafeMemberError as unsafe:
        if unsafe.why is Unsafe.OUTSIDE:
            raise ModelError(
                f"{where}: the member {unsafe.name!r} points outside the archive; a model's "
                "archive holds only relative paths."
            ) from None
        raise ModelError(
            f"{where}: the member {unsafe.name!r} is a link or special file; a model's "
            "archive holds only plain files."
        ) from None


def _write_member(tar: tarfile.TarFile, member: tarfile.TarInfo, target: Path, where: str) -> None:
    handle = tar.extractfile(member)
    if handle is None:  # only for non-files, which _checked_name has refused
        raise ModelError(f"{where}: {member.name} cannot be read as a file.")
    target.parent.mkdir(parents=True, exist_ok=True)
    with target.open("xb") as out:
        shutil.copyfileobj(handle, out, 1024 * 1024)
    if target.stat().st_size != member.size:
        raise ModelError(f"{where}: {member.name} is cut short (truncated archive).")


def _unpacked_too_much(where: str) -> None:
    raise ModelError(
        f"{where} unpacks to more than {MAX_UNPACKED_BYTES:,} bytes, more than a model's "
        "archive holds."
    )
