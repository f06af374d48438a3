"""What DeepRacer itself would make of a model: the notes an export carries.

A racer-tui model is written in DeepRacer's file formats, but not every model racer-tui can
train is one DeepRacer can run: DeepRacer's simulator requires exactly one camera among a
model's sensors (simapp `bundle/markov/boto/s3/files/model_metadata.py`,
`parse_model_metadata`: "model_metadata MUST contain only 1 camera sensor"), and VECTOR is
racer-tui's own sensor. The export says so, rather than hand out a file that looks ready.
"""

from __future__ import annotations

from sim.deepracer.files import ModelMetadata

# The camera sensor names simapp accepts in model_metadata.json.
DEEPRACER_CAMERAS = frozenset({"FRONT_FACING_CAMERA", "STEREO_CAMERAS", "LEFT_CAMERA"})


def export_notes(metadata: ModelMetadata) -> tuple[str, ...]:
    """One sentence per way DeepRacer itself would not run this model as exported."""
    sensors = [str(name) for name in metadata.to_json()["sensor"]]
    if "VECTOR" in sensors:
        what = "its sensor VECTOR is racer-tui's own (the car's place on the track as numbers)"
    elif sum(name in DEEPRACER_CAMERAS for name in sensors) != 1:
        what = f"its sensors are {' and '.join(sensors)}, without a camera"
    else:
        return ()
    return (
        f"This model races in racer-tui only: {what} and DeepRacer itself requires a camera "
        "(FRONT_FACING_CAMERA), so DeepRacer's simulator and cars cannot load it.",
    )
