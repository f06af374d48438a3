"""Model bundles: one `.racer-bundle` file that hands a model to another machine safely.

A bundle is a zip of fixed members: `manifest.json` (format version, name, created,
content hash, every other member's size and sha256), the DeepRacer files
(`model_metadata.json`, `hyperparameters.json`, `training_params.yaml`), a training
summary, the latest evaluation, `reward_function.py` and `policy.safetensors`.

A bundle may come from anyone, so reading one runs no code and trusts nothing: only the
expected member names, size limits per member and in total (zip bombs), sha256s that match
the manifest, JSON and YAML through the safe readers of `sim.deepracer.files`, and policy
weights that are a well-formed safetensors file (a JSON header plus raw tensor bytes,
checked here by hand, then by the safetensors library). Never pickle, never torch.load.
The reward function travels for information only: it is never executed on import or in
races, and an installed model trains with a template until the racer copies it over.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import zipfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

from safetensors import SafetensorError
from safetensors.numpy import load

from sim.deepracer.files import (
    HYPERPARAMETERS,
    MODEL_METADATA,
    REWARD_FUNCTION,
    TRAINING_PARAMS,
    DeepRacerFileError,
    EvaluationTrial,
    ModelMetadata,
    TrainingParams,
    evaluation_metrics_text,
    evaluation_stamp,
    parse_evaluation_metrics,
    parse_evaluation_physics,
    parse_hyperparameters,
    parse_json_object,
    parse_model_metadata,
    parse_training_params,
    read_evaluation_metrics,
    read_evaluation_physics,
    stamp_in,
)
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.names import is_valid_name
from sim.foundation.remedies import Fix, Note
from sim.garage.folder import (
    POLICY_FILE,
    TRAINING_SUMMARY_FILE,
    ModelError,
    ModelFolder,
    check_model_name,
    create_model,
    model_content_hash,
    write_export,
)
from sim.garage.imported import BUNDLE_SUFFIX, ImportResult
from sim.garage.options import DEFAULT_REWARD, DEFAULT_TRACK
from sim.garage.summary import read_summary_text, summary_text, training_summary
from sim.reward.template_files import shipped_template
from sim.tracks.catalog import list_tracks

BUNDLE_FORMAT = "racer-tui-bundle"
BUNDLE_VERSION = 1
MANIFEST = "manifest.json"
EVALUATION = "evaluation.json"
# The reward function of an installed bundle, kept for reading: nothing loads a .txt file.
BUNDLE_REWARD_FILE = "reward_function.bundle.txt"

# Largest size of each member (uncompressed) and of a whole bundle: a zip bomb stops here.
MEMBER_LIMITS = {
    MANIFEST: 64_000,
    MODEL_METADATA: 1_000_000,
    HYPERPARAMETERS: 64_000,
    TRAINING_PARAMS: 64_000,
    TRAINING_SUMMARY_FILE: 64_000,
    EVALUATION: 1_000_000,
    REWARD_FUNCTION: 1_000_000,
    POLICY_FILE: 64_000_000,
}
REQUIRED_MEMBERS = frozenset(MEMBER_LIMITS) - {EVALUATION}
MAX_BUNDLE_BYTES = 80_000_000  # compressed file, and uncompressed total
MAX_SAFETENSORS_HEADER = 1_000_000
# Tensor types a policy may hold, and their sizes: numbers only.
TENSOR_DTYPES = {"F16": 2, "F32": 4, "F64": 8}
_T = TypeVar("_T")


class BundleError(ModelError):
    """A bundle that is damaged, tampered with or not a bundle; the message names the file."""


@dataclass(frozen=True)
class Bundle:
    """A validated bundle, in memory. `reward_source` is text to read, never to run."""

    name: str
    created: str
    content_hash: str
    metadata: ModelMetadata
    hyperparameters: dict[str, float | int | str]
    training_params: TrainingParams
    training_summary: dict[str, Any]
    reward_source: str
    policy_bytes: bytes
    evaluation: tuple[EvaluationTrial, ...] | None = None
    evaluation_file: str | None = None  # the evaluation's file name in the exporting garage
    evaluation_physics: str | None = None  # the physics that timed its laps, when it says


# --- export ------------------------------------------------------------------------------


def bundle_path(out: Path) -> Path:
    """`out`, with the `.racer-bundle` suffix added if it lacks it."""
    out = Path(out).expanduser()
    return out if out.name.endswith(BUNDLE_SUFFIX) else out.with_name(out.name + BUNDLE_SUFFIX)


def export_bundle(folder: ModelFolder, out: Path, *, replace: bool = False) -> Path:
    """Write `folder` as a bundle at `out` (atomically); returns the path written.

    An existing file is only replaced when asked: a bundle handed out for a league night
    may be the only copy of a model someone trained.
    """
    target = bundle_path(out)
    if target.exists() and not replace:
        raise ModelError(
            f"{target} already exists; choose another file name, or replace it on purpose "
            "(`racer-tui model export --force`)."
        )
    problem = folder.car_archive_problem(
        "put in a .racer-bundle",
        f"share it as a car archive with `racer-tui model export {folder.name} --format car`",
    )
    if problem is not None:
        raise ModelError(problem)
    if not folder.has_policy():
        raise ModelError(
            f"model {folder.name!r} has no trained policy to export; train it first with "
            f"`racer-tui train {folder.name}`."
        )
    policy = folder.policy_file.read_bytes()
    check_safetensors(policy, str(folder.policy_file))
    metadata = folder.metadata()
    members: dict[str, bytes] = {
        MODEL_METADATA: _json_bytes(metadata.to_json()),
        HYPERPARAMETERS: _json_bytes(folder.hyperparameters()),
        TRAINING_PARAMS: folder.training_params().to_yaml().encode("utf-8"),
        TRAINING_SUMMARY_FILE: summary_text(training_summary(folder)).encode("utf-8"),
        REWARD_FUNCTION: folder.reward_source().encode("utf-8"),
        POLICY_FILE: policy,
    }
    evaluations = folder.evaluation_files()
    # Bundles name the evaluation `evaluation-<stamp>.json`, as they always have.
    evaluation_file = (
        f"evaluation-{stamp_in(evaluations[-1].name) or evaluation_stamp()}.json"
        if evaluations
        else None
    )
    if evaluations:
        trials = _from_deepracer(read_evaluation_metrics, evaluations[-1])
        # The physics that timed the laps travels with them (sim.physics.labels).
        timed_by = _from_deepracer(read_evaluation_physics, evaluations[-1])
        members[EVALUATION] = evaluation_metrics_text(trials, timed_by).encode("utf-8")
    for member, data in members.items():
        if len(data) > MEMBER_LIMITS[member]:
            raise ModelError(
                f"model {folder.name!r}: {member} is {len(data):,} bytes, more than the "
                f"{MEMBER_LIMITS[member]:,} a bundle may hold."
            )
    manifest = {
        "format": BUNDLE_FORMAT,
        "format_version": BUNDLE_VERSION,
        "name": folder.name,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "content_hash": model_content_hash(metadata, policy),
        "evaluation_file": evaluation_file,
        "files": [
            {"name": member, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()}
            for member, data in sorted(members.items())
        ],
    }
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(MANIFEST, _json_bytes(manifest))
        for member, data in sorted(members.items()):
            archive.writestr(member, data)
    write_export(target, buffer.getvalue())
    return target


def _json_bytes(data: object) -> bytes:
    return (json.dumps(data, indent=2, allow_nan=False) + "\n").encode("utf-8")


# --- reading -----------------------------------------------------------------------------


def read_bundle(path: Path) -> Bundle:
    """Read and validate a bundle completely; BundleError says what is wrong with it."""
    path = Path(path).expanduser()
    where = str(path)
    members = _read_members(path)
    manifest = _manifest(members, where)

    def text(member: str) -> str:
        try:
            return members[member].decode("utf-8")
        except UnicodeDecodeError:
            raise BundleError(f"{where}: {member} is not UTF-8 text.") from None

    def label(member: str) -> str:
        return f"{where} ({member})"

    metadata = _parsed(parse_model_metadata, text(MODEL_METADATA), label(MODEL_METADATA))
    policy = members[POLICY_FILE]
    check_safetensors(policy, label(POLICY_FILE))
    content_hash = model_content_hash(metadata, policy)
    if content_hash != manifest["content_hash"]:
        raise BundleError(
            f"{where}: the content hash does not match its metadata and policy; "
            "the bundle was changed after export, so ask for a fresh export."
        )
    evaluation = None
    evaluation_physics = None
    if EVALUATION in members:
        evaluation = _parsed(parse_evaluation_metrics, text(EVALUATION), label(EVALUATION))
        evaluation_physics = _parsed(parse_evaluation_physics, text(EVALUATION), label(EVALUATION))
    return Bundle(
        name=manifest["name"],
        created=manifest["created"],
        content_hash=content_hash,
        metadata=metadata,
        hyperparameters=_parsed(
            parse_hyperparameters, text(HYPERPARAMETERS), label(HYPERPARAMETERS)
        ),
        training_params=_parsed(
            parse_training_params, text(TRAINING_PARAMS), label(TRAINING_PARAMS)
        ),
        training_summary=read_summary_text(
            text(TRAINING_SUMMARY_FILE), label(TRAINING_SUMMARY_FILE)
        ),
        reward_source=text(REWARD_FUNCTION),
        policy_bytes=policy,
        evaluation=evaluation,
        evaluation_file=manifest["evaluation_file"] if evaluation is not None else None,
        evaluation_physics=evaluation_physics,
    )


def _read_members(path: Path) -> dict[str, bytes]:
    """Every member's bytes, after checking names and sizes before anything is inflated."""
    where = str(path)
    try:
        size = path.stat().st_size
        if size > MAX_BUNDLE_BYTES:
            raise BundleError(
                f"{where} is {size:,} bytes, more than the {MAX_BUNDLE_BYTES:,} a bundle may be."
            )
        data = path.read_bytes()
    except FileNotFoundError:
        raise BundleError(f"{where} does not exist; check the path.") from None
    except IsADirectoryError:
        raise BundleError(f"{where} is a folder, not a {BUNDLE_SUFFIX} file.") from None
    except OSError as error:
        raise BundleError(f"{where} cannot be read ({error.strerror}).") from None
    not_bundle = f"{where} is not a racer-tui bundle (a damaged or foreign file); export it again."
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            infos = archive.infolist()
            _check_listing(infos, where)
            members: dict[str, bytes] = {}
            for info in infos:
                with archive.open(info) as handle:
                    content = handle.read(MEMBER_LIMITS[info.filename] + 1)
                if len(content) > MEMBER_LIMITS[info.filename]:
                    raise BundleError(f"{where}: {info.filename} is larger than allowed.")
                members[info.filename] = content
    except BundleError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, RuntimeError):
        raise BundleError(not_bundle) from None
    except NotImplementedError:
        raise BundleError(f"{where} uses a zip compression racer-tui does not read.") from None
    return members


def _check_listing(infos: list[zipfile.ZipInfo], where: str) -> None:
    names = [info.filename for info in infos]
    for name in names:
        if name not in MEMBER_LIMITS:
            raise BundleError(
                f"{where} holds an unexpected member {name[:80]!r}; a bundle holds only "
                f"{', '.join(sorted(MEMBER_LIMITS))}, so it was not made by racer-tui."
            )
    if len(set(names)) != len(names):
        raise BundleError(f"{where} holds a member twice; it was tampered with.")
    missing = sorted(REQUIRED_MEMBERS - set(names))
    if missing:
        raise BundleError(f"{where} lacks {', '.join(missing)}; export the model again.")
    total = 0
    for info in infos:
        if info.flag_bits & 0x1:
            raise BundleError(f"{where}: {info.filename} is encrypted; bundles never are.")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise BundleError(f"{where}: {info.filename} uses an unsupported compression.")
        if info.file_size > MEMBER_LIMITS[info.filename]:
            raise BundleError(
                f"{where}: {info.filename} would unpack to {info.file_size:,} bytes, more than "
                f"the {MEMBER_LIMITS[info.filename]:,} allowed."
            )
        total += info.file_size
    if total > MAX_BUNDLE_BYTES:
        raise BundleError(f"{where} would unpack to {total:,} bytes, more than allowed.")


def _manifest(members: dict[str, bytes], where: str) -> dict[str, Any]:
    """The manifest, checked against the members: names, sizes and sha256s all agree."""
    label = f"{where} ({MANIFEST})"
    try:
        manifest = parse_json_object(members[MANIFEST].decode("utf-8"), label)
    except UnicodeDecodeError:
        raise BundleError(f"{label}: not UTF-8 text.") from None
    except DeepRacerFileError as error:
        raise BundleError(str(error)) from None
    if manifest.get("format") != BUNDLE_FORMAT:
        raise BundleError(f"{label}: not a racer-tui bundle manifest.")
    if manifest.get("format_version") != BUNDLE_VERSION:
        raise BundleError(
            f"{label}: bundle format version {manifest.get('format_version')!r} is not "
            f"{BUNDLE_VERSION}; update racer-tui or export the model again."
        )
    name = manifest.get("name")
    if not is_valid_name(name):
        raise BundleError(f"{label}: the model name is missing or not a valid name.")
    for key in ("created", "content_hash"):
        value = manifest.get(key)
        if not isinstance(value, str) or not 0 < len(value) <= 64:
            raise BundleError(f"{label}: {key} is missing or malformed.")
    evaluation_file = manifest.get("evaluation_file")
    if evaluation_file is not None and not _is_evaluation_name(evaluation_file):
        raise BundleError(f"{label}: evaluation_file is not an evaluation-*.json name.")
    if (EVALUATION in members) != (evaluation_file is not None):
        raise BundleError(f"{label}: the evaluation and its file name must come together.")
    listed = manifest.get("files")
    if not isinstance(listed, list) or not all(isinstance(item, dict) for item in listed):
        raise BundleError(f"{label}: files must be a list of {{name, size, sha256}}.")
    by_name = {str(item.get("name")): item for item in listed}
    expected = set(members) - {MANIFEST}
    if set(by_name) != expected or len(by_name) != len(listed):
        raise BundleError(f"{label}: the file list does not match the bundle's members.")
    for member in sorted(expected):
        data, item = members[member], by_name[member]
        if item.get("size") != len(data) or item.get("sha256") != hashlib.sha256(data).hexdigest():
            raise BundleError(
                f"{where}: {member} does not match the sha256 in its manifest; the bundle is "
                "damaged or was changed, so ask for a fresh export."
            )
    return manifest


def _is_evaluation_name(value: object) -> bool:
    if not isinstance(value, str) or not value.endswith(".json"):
        return False
    stem = value.removesuffix(".json")
    return stem.startswith("evaluation-") and is_valid_name(stem)


def _parsed(parser: Callable[[str, str], _T], text: str, where: str) -> _T:
    try:
        return parser(text, where)
    except DeepRacerFileError as error:
        raise BundleError(str(error)) from None


def _from_deepracer(reader: Callable[[Path], _T], path: Path) -> _T:
    try:
        return reader(path)
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None


def check_safetensors(data: bytes, where: str) -> dict[str, Any]:
    """The header of a safetensors file of number tensors; BundleError for anything else.

    Layout: 8 bytes little-endian header length, a JSON header {name: {dtype, shape,
    data_offsets}, "__metadata__": {str: str}}, then the tensors' raw bytes, packed with
    no gaps. Pickles, torch.save zips and truncated files all fail here.
    """
    not_tensors = (
        f"{where} is not a safetensors file of tensors (it may be a pickle, which racer-tui "
        "never loads); export the model again with racer-tui."
    )
    if len(data) < 8:
        raise BundleError(not_tensors)
    length = int.from_bytes(data[:8], "little")
    if not 2 <= length <= MAX_SAFETENSORS_HEADER or 8 + length > len(data):
        raise BundleError(not_tensors)
    try:
        header = json.loads(data[8 : 8 + length].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        raise BundleError(not_tensors) from None
    if not isinstance(header, dict):
        raise BundleError(not_tensors)
    spans: list[tuple[int, int]] = []
    for name, entry in header.items():
        if name == "__metadata__":
            if not isinstance(entry, dict) or not all(isinstance(v, str) for v in entry.values()):
                raise BundleError(f"{where}: the safetensors metadata must map text to text.")
            continue
        spans.append(_tensor_span(name, entry, where))
    body = len(data) - 8 - length
    if not spans:
        raise BundleError(f"{where} holds no tensors; export a trained model.")
    position = 0
    for begin, end in sorted(spans):
        if begin != position:
            raise BundleError(f"{where}: tensors overlap or leave gaps; the file is damaged.")
        position = end
    if position != body:
        raise BundleError(f"{where}: the tensor data does not fill the file; it is damaged.")
    _load_with_library(data, where)
    return header


def _tensor_span(name: str, entry: object, where: str) -> tuple[int, int]:
    bad = f"{where}: tensor {name[:80]!r} is malformed; the file is damaged."
    if not isinstance(entry, dict) or set(entry) != {"dtype", "shape", "data_offsets"}:
        raise BundleError(bad)
    dtype, shape, offsets = entry["dtype"], entry["shape"], entry["data_offsets"]
    if dtype not in TENSOR_DTYPES:
        raise BundleError(
            f"{where}: tensor {name[:80]!r} has type {str(dtype)[:16]!r}; policies hold "
            f"{', '.join(TENSOR_DTYPES)} numbers only."
        )
    if not isinstance(shape, list) or not all(_is_count(n) for n in shape):
        raise BundleError(bad)
    if not isinstance(offsets, list) or len(offsets) != 2 or not all(map(_is_count, offsets)):
        raise BundleError(bad)
    begin, end = offsets
    if end - begin != math.prod(shape) * TENSOR_DTYPES[dtype]:
        raise BundleError(bad)
    return begin, end


def _is_count(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _load_with_library(data: bytes, where: str) -> None:
    """A second opinion from the safetensors library itself (numpy, no code execution)."""

    try:
        load(data)
    except (SafetensorError, ValueError, TypeError):
        raise BundleError(f"{where}: the safetensors library rejects it as damaged.") from None


# --- install -----------------------------------------------------------------------------


def install_bundle(path: Path, name: str | None = None) -> ModelFolder:
    """Install a bundle as a new garage model (see `install_bundle_report`)."""
    return install_bundle_report(path, name=name).folder


def install_bundle_report(
    path: Path, name: str | None = None, track: str | None = None
) -> ImportResult:
    """Validate a bundle completely, then create a garage model from it.

    The bundle's reward function is kept as `reward_function.bundle.txt` for reading; the
    model's own `reward_function.py` is the default template, so nothing from the bundle
    ever runs. The track is `track`, else the bundle's if this garage knows it, else the
    default track (said in the notes).
    """
    bundle = read_bundle(path)
    chosen = name if name is not None else bundle.name
    check_model_name(chosen)
    notes: list[str] = []
    world = track if track is not None else _known_track(bundle.training_params, notes)
    notes.append(
        f"its reward function is kept for reading in {BUNDLE_REWARD_FILE} and is never run; "
        f"training uses the {DEFAULT_REWARD} template until you copy it over "
        f"{REWARD_FUNCTION}."
    )

    def populate(folder: ModelFolder) -> None:
        write_bytes_atomic(folder.policy_file, bundle.policy_bytes)
        write_bytes_atomic(
            folder.path / TRAINING_SUMMARY_FILE,
            summary_text(bundle.training_summary).encode("utf-8"),
        )
        write_bytes_atomic(folder.path / BUNDLE_REWARD_FILE, bundle.reward_source.encode("utf-8"))
        if bundle.evaluation is not None and bundle.evaluation_file is not None:
            stamp = stamp_in(bundle.evaluation_file) or evaluation_stamp()
            write_bytes_atomic(
                folder.evaluation_metrics_file(stamp),
                evaluation_metrics_text(bundle.evaluation, bundle.evaluation_physics).encode(
                    "utf-8"
                ),
            )

    folder = create_model(
        chosen,
        track=world,
        metadata=bundle.metadata,
        hyperparameters=bundle.hyperparameters,
        reward_source=shipped_template(DEFAULT_REWARD),
        max_minutes=bundle.training_params.max_minutes,
        populate=populate,
        notes={"INSTALLED_FROM": str(Path(path).expanduser().resolve())},
    )
    return ImportResult(folder, tuple(notes))


def _known_track(params: TrainingParams, notes: list[str]) -> str:

    known = {info.name for info in list_tracks()}
    if params.world_name in known:
        return params.world_name
    problem = (
        f"it trained on track {params.world_name!r}, which is not here: it is set up on "
        f"{DEFAULT_TRACK}"
    )
    notes.append(
        Note(f"{problem}; choose another with --track.", problem=problem, fix=Fix.CHOOSE_TRACK)
    )
    return DEFAULT_TRACK
