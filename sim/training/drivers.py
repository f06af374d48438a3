"""A racer's car as a driver: `reference` (the reference driver of the track), a
`.racer-bundle` file, or a garage model by name or folder path, and the drivers of race
records found by the hash of the exact car they name.

The command line's races, the league's replays and the app's nights all resolve entrants
here. Any problem is one RaceSetupError naming the entrant.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from sim.deepracer.files import DeepRacerFileError
from sim.foundation.remedies import RemedyError
from sim.garage.bundle import read_bundle
from sim.garage.folder import ModelError, ModelFolder, list_models, open_model
from sim.garage.imported import BUNDLE_SUFFIX
from sim.race.driver import REFERENCE_NAME, Driver, reference_driver
from sim.tracks.track import Track
from sim.training.errors import PolicyError


class RaceSetupError(RemedyError):
    """An entrant, option or output folder the race cannot use; one sentence to stderr
    (a library error's remedy kept, so the app's race view offers its own key)."""

    @classmethod
    def about(cls, error: Exception, prefix: str = "") -> RaceSetupError:
        """`error`, after `prefix`, with its remedy when it has one."""
        problem = error.problem if isinstance(error, RemedyError) else str(error)
        fix = error.fix if isinstance(error, RemedyError) else None
        return cls(f"{prefix}{error}", problem=f"{prefix}{problem}", fix=fix)


def resolve_driver(spec: str, track: Track) -> Driver:
    """The driver for MODEL: `reference`, a `.racer-bundle` file, or a garage model name
    (or model folder path). Any problem is a RaceSetupError naming the entrant."""
    if spec == REFERENCE_NAME:
        return reference_driver(track)
    try:
        if spec.endswith(BUNDLE_SUFFIX):
            bundle = read_bundle(Path(spec))
            return _policy_driver(spec, lambda drivers: drivers.driver_for_bundle(bundle))
        folder = open_model(spec)
        return model_driver(folder)
    except (ModelError, DeepRacerFileError) as error:
        raise RaceSetupError.about(error) from None


def model_driver(folder: ModelFolder) -> Driver:
    """A garage model's trained policy as a driver (torch is imported now: the app builds
    it inside a race's worker). A problem is a RaceSetupError naming the model."""
    return _policy_driver(folder.name, lambda drivers: drivers.driver_for_model(folder))


class DriversByHash:
    """Drivers found by the hash of the exact car (what race records name): the reference
    driver of a track, or the garage model whose content hash it is. The garage is hashed
    once, on the first trained model asked for."""

    def __init__(self) -> None:
        self._garage: dict[str, str] | None = None

    def __call__(self, model_hash: str, track: Track) -> Driver | None:
        if model_hash == f"{REFERENCE_NAME}:{track.content_hash}":
            return reference_driver(track)
        path = self._hashed().get(model_hash)
        return None if path is None else resolve_driver(path, track)

    def models_here(self) -> frozenset[str]:
        """The content hashes of the garage's models: their races are verifiable here
        (league.trust.standing)."""
        return frozenset(self._hashed())

    def _hashed(self) -> dict[str, str]:
        if self._garage is None:
            self._garage = {}
            for folder in list_models():
                try:
                    self._garage.setdefault(folder.content_hash(), str(folder.path))
                except (ModelError, OSError):
                    continue  # a damaged model is no one's race
        return self._garage


def _policy_driver(spec: str, build: Callable[[ModuleType], Driver]) -> Driver:
    """Load torch and the policy only now: the reference path never pays for them."""
    try:
        from sim.training import policy_driver  # noqa: PLC0415 (torch: only when a trained model races)
    except ImportError as error:
        raise RaceSetupError(
            f"cannot race {spec!r}: running a trained policy needs torch ({error})."
        ) from None
    try:
        return build(policy_driver)
    except PolicyError as error:
        raise RaceSetupError.about(error, f"cannot race {spec!r}: ") from None
