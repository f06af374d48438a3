"""Model bundles through S3: upload the models this league raced with, fetch others'.

Push (`racer-tui sync --bundles s3://BUCKET/PREFIX`): for every model named by a local
submission (a racer-tui garage model whose weights still hash to the submission's model
hash) or by a night entrant (a garage model, or a `.racer-bundle` file), upload its bundle
unless some bundle record already maps that model, then add a `bundle` record so every
league knows where it is. Exported bundles are cached under the data directory by model
hash, so a push interrupted after the upload sends the same bytes again (and S3 skips them).

Fetch (`racer-tui sync fetch-bundle HASH`): find the bundle record by model hash or file
hash (or an 8+ character prefix of either), download it (size-limited, checked against its
SHA-256, atomic), check that it holds the model it claims, and install it in the garage
through sim.garage.bundle: tensors and JSON only; its reward function is kept as text and
never run.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from league.assembler import RACER_TUI
from league.store import League
from league.sync.bundle_records import BundleInfo, add_bundle, find_bundles
from league.sync.errors import BundleError
from league.sync.kinds import BUNDLE_KIND
from league.sync.record import make_record
from league.sync.s3_bundles import BUNDLE_SUFFIX, S3BundleStore
from sim.foundation.home import data_home
from sim.foundation.ids import new_id
from sim.foundation.names import is_valid_name
from sim.garage.bundle import export_bundle, install_bundle_report, read_bundle
from sim.garage.folder import ModelError, open_model

CACHE_DIR = "sync-bundles"


@dataclass
class BundlePush:
    uploaded: int = 0
    already: int = 0  # the bucket had the very same bundle
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class _Candidate:
    model_hash: str | None  # None: whatever the model is now (night entrants)
    spec: str  # a garage model name, or a bundle file path


def push_bundles(league: League, store: S3BundleStore) -> BundlePush:
    """Upload the bundles of local models the league refers to and record where they are."""

    outcome = BundlePush()
    mapped = {row[0] for row in league.query("SELECT DISTINCT model_hash FROM sync_bundles")}
    for candidate in _candidates(league):
        try:
            found = _bundle_file(candidate)
        except ModelError as error:
            outcome.notes.append(f"{candidate.spec}: {error}")
            continue
        if found is None:
            continue  # another racer's model, or retrained since: not ours to send
        path, model_hash, name = found
        if model_hash in mapped:
            continue
        read_bundle(path)  # only well-formed bundles leave this machine
        ref, uploaded = store.put(path)
        outcome.uploaded += int(uploaded)
        outcome.already += int(not uploaded)
        body = {"model_hash": model_hash, "sha256": ref.sha256, "size": ref.size, "name": name}
        with league.transaction():
            add_bundle(league, make_record(BUNDLE_KIND, new_id(), body))
        mapped.add(model_hash)
    return outcome


def _candidates(league: League) -> list[_Candidate]:
    seen: set[tuple[str | None, str]] = set()
    found: list[_Candidate] = []
    rows = [
        *league.query(
            "SELECT DISTINCT model_hash, model_name FROM submissions WHERE source = ? "
            "ORDER BY model_name",
            (RACER_TUI,),
        ),
        *((None, row[0]) for row in league.query("SELECT DISTINCT model FROM night_entrants")),
    ]
    for model_hash, spec in rows:
        if (model_hash, spec) not in seen:
            seen.add((model_hash, spec))
            found.append(_Candidate(model_hash, spec))
    return found


def _bundle_file(candidate: _Candidate) -> tuple[Path, str, str] | None:
    """(bundle file, model hash, model name) for a model on this machine, else None."""

    spec = candidate.spec
    if spec.endswith(BUNDLE_SUFFIX):
        path = Path(spec)
        if not path.is_absolute() or not path.is_file():
            return None
        bundle = read_bundle(path)
        if not is_valid_name(bundle.name):
            return None
        return path, bundle.content_hash, bundle.name
    if not is_valid_name(spec):
        return None  # a folder path or `reference`: nothing to share
    try:
        folder = open_model(spec)
    except ModelError:
        return None  # not in this garage: another racer's model
    if not folder.has_policy():
        return None
    model_hash = folder.content_hash()
    if candidate.model_hash is not None and model_hash != candidate.model_hash:
        return None
    cache = data_home() / CACHE_DIR
    cache.mkdir(parents=True, exist_ok=True)
    path = cache / f"{model_hash}{BUNDLE_SUFFIX}"
    if not path.is_file():
        export_bundle(folder, path)
    return path, model_hash, folder.name


@dataclass(frozen=True)
class Installed:
    name: str
    bundle: BundleInfo
    notes: tuple[str, ...]


def fetch_bundle(
    league: League, store: S3BundleStore, spec: str, name: str | None = None
) -> Installed:
    """Download the bundle `spec` names and install it as a garage model."""

    matches = find_bundles(league, spec)
    files = {match.sha256 for match in matches}
    if not matches:
        raise BundleError(
            f"no bundle is known for {spec[:80]!r}: pull first (racer-tui sync --pull), or ask "
            "the model's racer to sync with --bundles s3://BUCKET/PREFIX"
        )
    if len(files) > 1:
        raise BundleError(
            f"{spec!r} matches {len(files)} bundles: give more characters of the hash"
        )
    info = matches[0]
    with tempfile.TemporaryDirectory(prefix="racer-tui-bundle-") as tmp:
        path = Path(tmp) / f"{info.sha256}{BUNDLE_SUFFIX}"
        store.fetch(info.sha256, path)
        bundle = read_bundle(path)
        if bundle.content_hash != info.model_hash:
            raise BundleError(
                f"the bundle {info.sha256[:12]} holds another model than its record says: "
                "it was not installed"
            )
        result = install_bundle_report(path, name=name or info.name)
    return Installed(result.folder.name, info, result.notes)
