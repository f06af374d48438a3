"""What importing a model gives back, whatever it came from (a DeepRacer folder, a bundle,
a car archive), and the bundle file's suffix the importers and the dispatcher name."""

from __future__ import annotations

from dataclasses import dataclass

from sim.garage.folder import ModelFolder

BUNDLE_SUFFIX = ".racer-bundle"


@dataclass(frozen=True)
class ImportResult:
    """The new model and what the racer should know about how it was filled in."""

    folder: ModelFolder
    notes: tuple[str, ...] = ()
