"""`racer-tui model import PATH`: whichever kind of model PATH is, into the garage.

A `.tar.gz` is told by its contents (`model_archive`): a car archive goes to
`car_archive_import`, DeepRacer on AWS's virtual model to `deepracer_import` once unpacked;
a `.racer-bundle` goes to `bundle`, a folder to `deepracer_import`; each says what it
filled in.
"""

from __future__ import annotations

import tempfile
import zipfile
from pathlib import Path

from sim.car_archive.file_names import is_car_archive_name
from sim.foundation.remedies import echoed_path
from sim.garage.bundle import install_bundle_report
from sim.garage.car_archive_import import import_car_archive
from sim.garage.deepracer_import import import_deepracer_folder
from sim.garage.folder import ModelError
from sim.garage.imported import BUNDLE_SUFFIX, ImportResult
from sim.garage.model_archive import ArchiveKind, unpack_model_archive


def import_model(
    path: Path, name: str | None = None, track: str | None = None, *, untrained: bool = False
) -> ImportResult:
    """A DeepRacer model folder, a `.racer-bundle` file or a DeepRacer car archive
    (`.tar.gz`), as a new garage model."""
    source = Path(path).expanduser()
    try:
        is_file, is_dir = source.is_file(), source.is_dir()
    except OSError:  # a name no file can have (too long, say): there is none
        is_file = is_dir = False
    if is_file and is_car_archive_name(source):
        return _import_archive(source, name, track, untrained=untrained)
    if is_file and not _could_be_a_bundle(source):
        raise ModelError(
            f"{echoed_path(source)} is not a model racer-tui can import (neither a "
            f"{BUNDLE_SUFFIX} file, which is a zip archive, nor a car archive); give a "
            "DeepRacer model folder, a bundle exported by racer-tui or a car archive (.tar.gz)."
        )
    if is_file:
        return install_bundle_report(source, name=name, track=track)
    if is_dir:
        return import_deepracer_folder(source, name=name, track=track, untrained=untrained)
    raise ModelError(
        f"{echoed_path(source)} does not exist; give a DeepRacer model folder, a "
        f"{BUNDLE_SUFFIX} file or a car archive (.tar.gz)."
    )


def _import_archive(
    source: Path, name: str | None, track: str | None, *, untrained: bool
) -> ImportResult:
    """A `.tar.gz` by what it holds: a car archive, or DeepRacer on AWS's virtual model
    (unpacked into a scratch folder, imported as a DeepRacer folder, then removed)."""
    with tempfile.TemporaryDirectory(prefix="racer-import-") as scratch:
        if unpack_model_archive(source, Path(scratch)) is ArchiveKind.VIRTUAL:
            return import_deepracer_folder(
                Path(scratch), name=name, track=track, untrained=untrained, origin=source
            )
    return import_car_archive(source, name=name, track=track)


def _could_be_a_bundle(source: Path) -> bool:
    """Named as a bundle, or a zip archive (a bundle renamed): the bundle's reader then says
    what is wrong with it. Anything else is some other file picked by mistake."""
    if source.name.endswith(BUNDLE_SUFFIX):
        return True
    try:
        return zipfile.is_zipfile(source)
    except OSError:
        return True  # unreadable: the bundle's reader says so in its words
