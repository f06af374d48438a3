"""The one place that turns a track name into a track.

Three kinds of track, listed in this order:
- built-in: racer-tui's own designs, in the `tracks` package with an `index.yaml`;
- official: AWS DeepRacer's 127 track files in `tracks/official/` with their catalog
  (`sim.tracks.official`), found by the simulator's world name (`reinvent_base`) or by the
  console's name (`re:Invent 2018`, any case);
- imported: a racer's own tracks in `sim.foundation.home.user_tracks_dir()` as `<name>.npy` with an
  optional `<name>.yaml` sidecar (description and the facts `list_tracks` shows).
Listing never loads an array, and importing this module loads no geometry library, so
`racer-tui tracks list` starts fast. The .npy file is what makes an imported track exist:
the sidecar is written first, so a crash between the two writes leaves no half-imported
track. A track's identity in the league is its content hash, so an official track and the
same file imported by hand are one track.
"""

from __future__ import annotations

import difflib
import functools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import yaml

import tracks
from sim.foundation.atomic import write_text_atomic
from sim.foundation.home import user_tracks_dir
from sim.foundation.names import NAME_PATTERN, NAME_RULE
from sim.foundation.remedies import Fix, Note, echoed
from sim.tracks.errors import TrackError
from sim.tracks.official import OfficialTrack, official_tracks

if TYPE_CHECKING:
    from sim.tracks.track import Track

INDEX_FILE = "index.yaml"
_SAFE_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
# The track of the league rule every DeepRacer racer knows ("4 minutes for your best lap on
# the re:Invent track"): new models, races and league nights start here.
DEFAULT_TRACK = "reinvent_base"
_NAME = NAME_PATTERN

TrackKind = Literal["built-in", "official", "imported"]


@dataclass(frozen=True)
class TrackInfo:
    """What a track list shows about one track, without loading its array."""

    name: str
    description: str
    length_m: float
    width_m: float
    direction: str
    kind: TrackKind
    path: Path
    console_name: str = ""  # official tracks: the name the DeepRacer console shows
    release_date: str = ""  # official tracks: YYYY-MM-DD when the console released it
    content_hash: str = ""  # Track.content_hash when known without loading the array
    lappable: bool = True  # False for a straight piece of road (it has no laps)

    @property
    def builtin(self) -> bool:
        """One of racer-tui's own designs."""
        return self.kind == "built-in"

    @property
    def title(self) -> str:
        """How a chooser names it: "re:Invent 2018 (reinvent_base)", or just the name."""
        return f"{self.console_name} ({self.name})" if self.console_name else self.name


def builtin_dir() -> Path:
    return Path(tracks.__file__).parent


def list_tracks() -> list[TrackInfo]:
    """Built-in tracks in index order, official tracks by release date (the newest last, the
    console never listed last) then world name, then the racer's imported tracks by name."""
    return builtin_tracks() + official_track_infos() + user_tracks()


def builtin_tracks() -> list[TrackInfo]:
    return list(_builtin_infos())


def official_track_infos() -> list[TrackInfo]:
    return list(_official_infos())


# Package data never changes while racer-tui runs, and every lookup by name lists it: read
# once, it costs a race or a replay in the app nothing instead of 8 ms of YAML parsing.
@functools.cache
def _builtin_infos() -> tuple[TrackInfo, ...]:
    directory = builtin_dir()
    entries = _read_yaml(directory / INDEX_FILE)
    if not isinstance(entries, list):
        raise TrackError(f"{directory / INDEX_FILE}: is not a list of tracks; reinstall racer-tui.")
    return tuple(_info(entry, directory / str(entry["file"]), kind="built-in") for entry in entries)


@functools.cache
def _official_infos() -> tuple[TrackInfo, ...]:
    ordered = sorted(official_tracks(), key=lambda t: (t.release_date or "9999", t.world_name))
    return tuple(_official_info(track) for track in ordered)


def user_tracks() -> list[TrackInfo]:
    return [_user_info(npy) for npy in sorted(user_tracks_dir().glob("*.npy"))]


def find_track_info(name: str) -> TrackInfo:
    """The listed track a name means, or TrackError with the closest names.

    An exact name first (built-in, then official, then imported: an imported copy never
    hides an official track), then the same name in any case, then an official track's
    console name in any case.
    """
    infos = list_tracks()
    for info in infos:
        if info.name == name:
            return info
    folded = name.casefold().strip()
    for info in infos:
        if info.name.casefold() == folded:
            return info
    by_console = _console_matches(folded)
    if len(by_console) == 1:
        return _official_info(by_console[0])
    if by_console:
        choices = " or ".join(f"{track.world_name} ({track.direction})" for track in by_console)
        raise TrackError(f"{echoed(name)} is {len(by_console)} tracks; give one of: {choices}.")
    raise _unknown_name(name, infos)


def _load_track(
    path: Path | str, name: str | None = None, *, description: str = "", reverse: bool = False
) -> Track:
    """`sim.tracks.track.load_track`, imported on the first read of a track file: it loads
    numpy and shapely, which listing the catalogs (`tracks list`, the app's start) does not
    need."""
    from sim.tracks.track import load_track  # noqa: PLC0415 (start-up: see the docstring)

    return load_track(path, name, description=description, reverse=reverse)


def resolve_track(name_or_path: str) -> Track:
    """A track by name (see `find_track_info`), or the path of a DeepRacer .npy file."""
    path = Path(name_or_path).expanduser()
    if not _NAME.fullmatch(name_or_path) and (path.suffix == ".npy" or _is_file(path)):
        return _load_track(path)
    try:
        info = find_track_info(name_or_path)
    except TrackError:
        if _is_file(path):
            return _load_track(path)
        raise
    if not info.lappable:
        raise TrackError(
            f"{info.name} is a straight piece of road, not a loop; racer-tui races laps, "
            f"so choose a loop such as {DEFAULT_TRACK} (re:Invent 2018)."
        )
    return _load_track(info.path, info.name, description=info.description)


def _is_file(path: Path) -> bool:
    """Whether `path` is a file; False, not an error, for a name no file can have (too long
    for the file system, say), which is then looked up as a track name."""
    try:
        return path.is_file()
    except OSError:
        return False


def find_track_by_hash(content_hash: str) -> TrackInfo | None:
    """The listed track with this content hash (the league's track identity), or None.

    Official and sidecar'd tracks know their hash without loading; only imported files
    copied in by hand (no sidecar hash) are loaded to compare.
    """
    unknown: list[TrackInfo] = []
    for info in list_tracks():
        if info.content_hash == content_hash:
            return info
        if not info.content_hash and info.lappable:
            unknown.append(info)
    for info in unknown:
        try:
            if _load_track(info.path, info.name).content_hash == content_hash:
                return info
        except TrackError:
            continue  # a damaged imported track: the tracks section says what is wrong
    return None


def import_track(
    path: Path, name: str | None = None, *, reverse: bool = False, description: str = ""
) -> TrackInfo:
    """Validate a DeepRacer .npy file and keep a copy under `name` (default: the file's stem).

    A file that is already shipped under that name (an official track's own file, imported
    by habit) is not copied again: the shipped track is returned, and `kind` says so.
    """
    source = Path(path).expanduser()
    chosen = name if name is not None else source.stem
    _check_name(chosen)
    track = _load_track(source, chosen, description=description, reverse=reverse)
    shipped = _shipped_named(chosen)
    if shipped is not None and shipped.content_hash == track.content_hash:
        return shipped
    _check_new_name(chosen)
    return _save(track, extra={"source": str(source.resolve()), "reversed": reverse})


def save_user_track(track: Track) -> TrackInfo:
    """Keep a built or generated track; saving the very same track again is a no-op."""
    _check_name(track.name)
    existing = _user_path(track.name)
    if existing.exists() and _load_track(existing).content_hash == track.content_hash:
        return _user_info(existing)
    _check_new_name(track.name)
    return _save(track, extra={})


def _console_matches(folded: str) -> list[OfficialTrack]:
    """Official tracks a console name or console track id means: the console's own variant
    when there is one, else every direction variant (the caller asks which)."""
    named = [
        track
        for track in official_tracks()
        if folded in (track.console_name.casefold(), track.console_track.casefold())
        and track.closed
    ]
    main = [track for track in named if track.world_name == track.console_track]
    return main or named


def _unknown_name(name: str, infos: list[TrackInfo]) -> TrackError:
    by_fold: dict[str, str] = {}
    for info in infos:
        by_fold.setdefault(info.name.casefold(), info.name)
        if info.console_name:
            by_fold.setdefault(info.console_name.casefold(), info.console_name)
    close = difflib.get_close_matches(name.casefold(), list(by_fold), n=4, cutoff=0.6)
    near = ", ".join(repr(by_fold[key]) for key in close)
    problem = f"there is no track named {echoed(name)}" + (
        f" (close names: {near})" if close else ""
    )
    return TrackError(
        f"{problem}; give a name that `racer-tui tracks list` shows, or the path of a "
        "DeepRacer .npy file (`racer-tui tracks import FILE` keeps one).",
        problem=problem,
        fix=Fix.IMPORT_TRACK,
    )


# --- names ----------------------------------------------------------------------------


def _check_name(name: str) -> None:
    problem = _name_rule_problem(name)
    if problem is not None:
        raise TrackError(f"{problem}, for example with --name.", problem=problem, fix=Fix.RENAME)


def _check_new_name(name: str) -> None:
    problem = new_name_problem(name)
    if problem is not None:
        raise TrackError(_renamed(problem), problem=problem, fix=Fix.RENAME)


def _renamed(problem: str) -> str:
    return f"{problem}; choose another name with --name."


def _name_rule_problem(name: str) -> str | None:
    if _NAME.fullmatch(name):
        return None
    return f"{echoed(name)} cannot be a track name; use {NAME_RULE}"


def new_name_problem(name: str) -> str | None:
    """Why `name` cannot name a new track, without the remedy (each front end asks for
    another name its own way), or None."""
    rule = _name_rule_problem(name)
    if rule is not None:
        return rule
    # Compared without case: on macOS and Windows "Oval.npy" and "oval.npy" are one file.
    folded = name.casefold()
    shipped = _shipped_named(name)
    if shipped is not None:
        return f"{echoed(name)} is the name of {_a(shipped.kind)} track"
    for npy in user_tracks_dir().glob("*.npy"):
        if npy.stem.casefold() == folded:
            return f"a track named {npy.stem!r} is already imported"
    return None


def import_problem(path: Path, name: str | None = None) -> str | None:
    """What would stop `import_track(path, name)`, or None when it would work: the file is
    read and checked, nothing is kept. A front end asks this while the racer can still
    change the path or the name; a name's problem is a Note whose fix is Fix.RENAME."""
    source = Path(path).expanduser()
    chosen = name if name is not None else source.stem
    problem = _name_rule_problem(chosen)
    if problem is None:
        try:
            track = _load_track(source, chosen)
        except TrackError as error:
            return str(error)
        shipped = _shipped_named(chosen)
        if shipped is not None and shipped.content_hash == track.content_hash:
            return None  # the shipped file itself: import_track says it is already here
        problem = new_name_problem(chosen)
    return None if problem is None else Note(_renamed(problem), problem=problem, fix=Fix.RENAME)


def _user_path(name: str) -> Path:
    return user_tracks_dir() / f"{name}.npy"


# --- files ----------------------------------------------------------------------------


def _save(track: Track, extra: dict[str, object]) -> TrackInfo:
    npy = _user_path(track.name)
    sidecar: dict[str, object] = {**track.summary(), **extra, "sha256": track.content_hash}
    write_text_atomic(npy.with_suffix(".yaml"), yaml.safe_dump(sidecar, sort_keys=False))
    track.save(npy)
    return _info(sidecar, npy, kind="imported")


def _user_info(npy: Path) -> TrackInfo:
    meta = _read_yaml(npy.with_suffix(".yaml"))
    facts = meta if isinstance(meta, dict) else {}
    if not _has_facts(facts):
        facts = _facts_from_file(npy, facts)
    info = _info({**facts, "name": npy.stem}, npy, kind="imported")
    if _shadowed(npy.stem):
        note = "hidden by the track of the same name; import the file again under another name"
        return TrackInfo(**{**info.__dict__, "description": note})
    return info


def _shadowed(name: str) -> bool:
    """An imported track named like a built-in or official one (imported before racer-tui
    shipped it): names find the shipped track, so this copy needs another name."""
    return _shipped_named(name) is not None


def _shipped_named(name: str) -> TrackInfo | None:
    """The built-in or official track with this name in any case (one file on macOS)."""
    return _shipped_by_folded_name().get(name.casefold())


@functools.cache
def _shipped_by_folded_name() -> dict[str, TrackInfo]:
    return {info.name.casefold(): info for info in _builtin_infos() + _official_infos()}


def _has_facts(meta: dict[str, Any]) -> bool:
    return all(
        isinstance(meta.get(key), int | float) and math.isfinite(meta[key])
        for key in ("length_m", "width_m")
    ) and isinstance(meta.get("direction"), str)


def _facts_from_file(npy: Path, meta: dict[str, Any]) -> dict[str, Any]:
    """Facts for a track copied in by hand, without a sidecar; unreadable files still list."""
    description = str(meta.get("description", ""))
    try:
        summary = _load_track(npy, npy.stem, description=description).summary()
    except TrackError as exc:
        return {"description": f"cannot be used: {exc}", "length_m": 0.0, "width_m": 0.0}
    return summary


def _info(entry: dict[str, Any], path: Path, *, kind: TrackKind) -> TrackInfo:
    return TrackInfo(
        name=str(entry["name"]),
        description=str(entry.get("description") or ""),
        length_m=float(entry.get("length_m", 0.0)),
        width_m=float(entry.get("width_m", 0.0)),
        direction=str(entry.get("direction", "unknown")),
        kind=kind,
        path=path,
        content_hash=str(entry.get("sha256") or ""),
    )


def _official_info(track: OfficialTrack) -> TrackInfo:
    released = f"released {track.release_date}" if track.release_date else "never in the console"
    what = "AWS DeepRacer track" if track.closed else "AWS DeepRacer's straight test road"
    return TrackInfo(
        name=track.world_name,
        description=f"{what}, {released}",
        length_m=track.length_m,
        width_m=track.width_m,
        direction=track.direction,
        kind="official",
        path=track.path,
        console_name=track.console_name,
        release_date=track.release_date,
        content_hash=track.sha256,
        lappable=track.closed,
    )


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def _read_yaml(path: Path) -> Any:
    """Parsed YAML (safe_load: a track index is data, never objects), or None when unusable."""
    try:
        # libyaml's safe loader when the installed PyYAML has it: the same data, 10x faster.
        return yaml.load(path.read_text(encoding="utf-8"), Loader=_SAFE_LOADER)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
