"""`racer-tui model import FILE.tar.gz`: a DeepRacer car archive as a garage model.

The archive is what a physical DeepRacer loads (racer-tui's own car export, the DeepRacer
console's or DeepRacer on AWS's physical-model download, deepracer-for-cloud's car upload):
`model_metadata.json` and one frozen TensorFlow graph. It is read as untrusted input by
`sim.car_archive.archive` (size limits, plain members only, an op allow-list; nothing in it is
executed), its graph is run once on a blank frame to prove racer-tui can drive with it, and
the archive is kept whole in the model folder (`car-model.tar.gz`). The model then
evaluates, races and exports for the car like any other; it cannot be trained or cloned,
since its weights are TensorFlow's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from sim.car_archive.archive import read_car_archive
from sim.car_archive.errors import CarModelError
from sim.deepracer.files import default_hyperparameters
from sim.foundation.remedies import Fix, Note
from sim.garage.folder import ModelError, ModelFolder, check_model_name, create_model
from sim.garage.imported import ImportResult
from sim.garage.model_archive import download_name
from sim.garage.options import DEFAULT_REWARD, DEFAULT_TRACK
from sim.reward.template_files import shipped_template


def import_car_archive(
    path: Path, name: str | None = None, track: str | None = None
) -> ImportResult:
    """A new garage model that drives with the car archive at `path`."""
    from sim.car_archive.policy import CarPolicy  # noqa: PLC0415 (torch: runs the graph, only now)

    source = Path(path).expanduser()
    try:
        archive = read_car_archive(source)
        CarPolicy(archive)  # the graph runs on a blank frame, with the outputs the space needs
    except CarModelError as error:
        raise ModelError(str(error)) from None
    chosen = name if name is not None else download_name(source)
    try:
        check_model_name(chosen)
    except ModelError:
        if name is not None:
            raise
        problem = f"the file name {chosen!r} cannot be a model name"
        raise ModelError(
            f"{problem}; give one with --name.", problem=problem, fix=Fix.RENAME
        ) from None
    notes: list[str] = [
        "it drives with the archive's TensorFlow graph, which racer-tui runs as the car "
        "would (one greyscale frame; the most likely action, or a continuous space's mean); "
        "it races and exports for the car but cannot be trained here.",
    ]
    if track is None:
        problem = f"a car archive does not say where it trained: it is set up on {DEFAULT_TRACK}"
        notes.append(
            Note(
                f"{problem}; choose another with --track or in the model editor.",
                problem=problem,
                fix=Fix.CHOOSE_TRACK,
            )
        )

    def populate(folder: ModelFolder) -> None:
        shutil.copyfile(source, folder.car_archive_file)
        try:
            copied = read_car_archive(folder.car_archive_file).content_hash
        except CarModelError:
            copied = ""
        if copied != archive.content_hash:
            raise ModelError(f"{source} changed while it was imported; import it again.")

    folder = create_model(
        chosen,
        track=track or DEFAULT_TRACK,
        metadata=archive.metadata,
        hyperparameters=default_hyperparameters(),
        reward_source=shipped_template(DEFAULT_REWARD),
        populate=populate,
        notes={"IMPORTED_FROM": str(source.resolve())},
    )
    return ImportResult(folder, tuple(notes))
