"""The boxes and bot cars of a race as the camera draws them: solids in DeepRacer's tones.

An object field only knows where its objects stand; drawing them is the camera's business.
Objects that stand still are one `Solids` until they are placed again, so the drawing is
kept per field and rebuilt only when the field's `placed` count or the cars asked change;
objects that move every step (a race's other cars) keep their sizes and tones and only
take their new places.
"""

from __future__ import annotations

import weakref

import numpy as np
from numpy.typing import NDArray

from sim.physics.objects.field import ObjectField
from sim.sensors import camera_scene as scene
from sim.sensors.camera import Solids

_DRAWN: weakref.WeakKeyDictionary[ObjectField, tuple[tuple[int, bytes], Solids]] = (
    weakref.WeakKeyDictionary()
)


def object_solids(field: ObjectField, cars: NDArray[np.intp]) -> Solids:
    """`cars`' objects in `field` as the camera draws them (rows in `cars`' order)."""
    key = (field.placed, np.asarray(cars, dtype=np.intp).tobytes())
    kept = _DRAWN.get(field)
    if kept is not None and kept[0] == key:
        return kept[1]
    if kept is not None and kept[0][1] == key[1]:  # the same cars' objects, moved
        solids = kept[1].placed_at(field.x[cars], field.y[cars], field.heading[cars])
        _DRAWN[field] = (key, solids)
        return solids
    shape, k = field.shape, field.count
    side, top = (
        (scene.BOT_CAR_SIDE, scene.BOT_CAR_TOP) if shape.is_car else (scene.BOX_SIDE, scene.BOX_TOP)
    )
    solids = Solids(
        x=field.x[cars],
        y=field.y[cars],
        heading=field.heading[cars],
        length=np.full(k, shape.length),
        width=np.full(k, shape.width),
        height=np.full(k, shape.height),
        side_tone=np.full(k, side, dtype=np.uint8),
        top_tone=np.full(k, top, dtype=np.uint8),
    )
    _DRAWN[field] = (key, solids)
    return solids
