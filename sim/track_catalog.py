"""The one place that turns a track name into a track.

Built-in tracks ship in the `tracks` package with an `index.yaml`; a racer's own tracks
live in `sim.home.user_tracks_dir()` as `<name>.npy` with an optional `<name>.yaml` sidecar
(description and the facts `list_tracks` shows, so listing never loads every array).
The .npy file is what makes a track exist: the sidecar is written first, so a crash
between the two writes leaves no half-imported track.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

import tracks
from sim.atomic import write_text_atomic
from sim.home import user_tracks_dir
from sim.names import NAME_PATTERN, NAME_RULE
from sim.track import Track, TrackError, load_track

INDEX_FILE = "index.yaml"
_NAME = NAME_PATTERN


@dataclass(frozen=True)
class TrackInfo:
    """What a track list shows about one track, without loading its array."""

    name: str
    description: str
    length_m: float
    width_m: float
    direction: str
    builtin: bool
    path: Path


def builtin_dir() -> Path:
    return Path(tracks.__file__).parent


def list_tracks() -> list[TrackInfo]:
    """Built-in tracks in index order, then the racer's imported tracks by name."""
    return builtin_tracks() + user_tracks()


def builtin_tracks() -> list[TrackInfo]:
    directory = builtin_dir()
    entries = _read_yaml(directory / INDEX_FILE)
    if not isinstance(entries, list):
        raise TrackError(f"{directory / INDEX_FILE}: is not a list of tracks; reinstall racer-tui.")
    return [_info(entry, directory / str(entry["file"]), builtin=True) for entry in entries]


def user_tracks() -> list[TrackInfo]:
    return [_user_info(npy) for npy in sorted(user_tracks_dir().glob("*.npy"))]


def resolve_track(name_or_path: str) -> Track:
    """A built-in track name, an imported track name, or the path of a DeepRacer .npy file."""
    known = list_tracks()
    for info in known:
        if info.name == name_or_path:
            return load_track(info.path, info.name, description=info.description)
    path = Path(name_or_path).expanduser()
    if not _NAME.fullmatch(name_or_path) or path.is_file():
        return load_track(path)
    names = ", ".join(info.name for info in known)
    raise TrackError(
        f"there is no track named {name_or_path!r} (the tracks are: {names}); give one of "
        "these names, the path of a DeepRacer .npy file, or import a file with "
        "`racer-tui tracks import FILE`."
    )


def import_track(
    path: Path, name: str | None = None, *, reverse: bool = False, description: str = ""
) -> TrackInfo:
    """Validate a DeepRacer .npy file and keep a copy under `name` (default: the file's stem)."""
    source = Path(path).expanduser()
    chosen = name if name is not None else source.stem
    _check_new_name(chosen)
    track = load_track(source, chosen, description=description, reverse=reverse)
    return _save(track, extra={"source": str(source.resolve()), "reversed": reverse})


def save_user_track(track: Track) -> TrackInfo:
    """Keep a built or generated track; saving the very same track again is a no-op."""
    _check_name(track.name)
    existing = _user_path(track.name)
    if existing.exists() and load_track(existing).content_hash == track.content_hash:
        return _user_info(existing)
    _check_new_name(track.name)
    return _save(track, extra={})


# --- names ----------------------------------------------------------------------------


def _check_name(name: str) -> None:
    if not _NAME.fullmatch(name):
        raise TrackError(
            f"{name!r} cannot be a track name; use {NAME_RULE}, for example with --name."
        )


def _check_new_name(name: str) -> None:
    _check_name(name)
    # Compared without case: on macOS and Windows "Oval.npy" and "oval.npy" are one file.
    folded = name.casefold()
    if any(info.name.casefold() == folded for info in builtin_tracks()):
        raise TrackError(
            f"{name!r} is the name of a built-in track; choose another name with --name."
        )
    for npy in user_tracks_dir().glob("*.npy"):
        if npy.stem.casefold() == folded:
            raise TrackError(
                f"a track named {npy.stem!r} is already imported; choose another name with --name."
            )


def _user_path(name: str) -> Path:
    return user_tracks_dir() / f"{name}.npy"


# --- files ----------------------------------------------------------------------------


def _save(track: Track, extra: dict[str, object]) -> TrackInfo:
    npy = _user_path(track.name)
    sidecar: dict[str, object] = {**track.summary(), **extra, "sha256": track.content_hash}
    write_text_atomic(npy.with_suffix(".yaml"), yaml.safe_dump(sidecar, sort_keys=False))
    track.save(npy)
    return _info(sidecar, npy, builtin=False)


def _user_info(npy: Path) -> TrackInfo:
    meta = _read_yaml(npy.with_suffix(".yaml"))
    facts = meta if isinstance(meta, dict) else {}
    if not _has_facts(facts):
        facts = _facts_from_file(npy, facts)
    return _info({**facts, "name": npy.stem}, npy, builtin=False)


def _has_facts(meta: dict[str, Any]) -> bool:
    return all(
        isinstance(meta.get(key), int | float) and math.isfinite(meta[key])
        for key in ("length_m", "width_m")
    ) and isinstance(meta.get("direction"), str)


def _facts_from_file(npy: Path, meta: dict[str, Any]) -> dict[str, Any]:
    """Facts for a track copied in by hand, without a sidecar; unreadable files still list."""
    description = str(meta.get("description", ""))
    try:
        summary = load_track(npy, npy.stem, description=description).summary()
    except TrackError as exc:
        return {"description": f"cannot be used: {exc}", "length_m": 0.0, "width_m": 0.0}
    return summary


def _info(entry: dict[str, Any], path: Path, *, builtin: bool) -> TrackInfo:
    return TrackInfo(
        name=str(entry["name"]),
        description=str(entry.get("description") or ""),
        length_m=float(entry.get("length_m", 0.0)),
        width_m=float(entry.get("width_m", 0.0)),
        direction=str(entry.get("direction", "unknown")),
        builtin=builtin,
        path=path,
    )


def _read_yaml(path: Path) -> Any:
    """Parsed YAML (safe_load: a track index is data, never objects), or None when unusable."""
    try:
        return yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
