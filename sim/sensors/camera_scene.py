"""What DeepRacer's simulated camera sees, as facts: the scene's tones, line widths and walls.

Every track is dressed the way DeepRacer dresses re:Invent 2018 (`reinvent_base`, the
default track): a dark, grainy road with white bands along both edges and an orange
dashed centre line, on a green field closed by dark walls 1 m tall. Sources, in
aws-deepracer-community/deepracer-simapp:

* `bundle/meshes/reinvent/reinvent_base.dae`: the road, the two edge bands (`ol`, `il`),
  the centre dashes (`cl`), the field and the walls as meshes. The bands are 0.0762 m
  wide and lie on the road, their outer edge on the track file's border; the 174 dashes
  are 0.0508 m long, 0.0254 m wide and repeat every 0.1016 m; the field is the road's
  bounding box grown by 0.91 m on every side (0.903-0.916 m), and the walls stand on its
  edge, 1 m tall, facing inwards.
* `bundle/meshes/reinvent/textures/*.png` (road, outerLine, centerLine, field, wall) and
  `bundle/worlds/reinvent_base.world` (the sun shining towards (-0.5, 0.1, -0.9), a point
  light above the origin): lit, flat ground comes out about 1.1 times its texture's
  brightness, and only the wall that faces +x is in the sun.

Tones are greyscale after DeepRacer's grey formula (0.2989 R + 0.5870 G + 0.1140 B), read
off a frame of DeepRacer's simulator camera (deepracer-utils' `dr-demo-1.png`; the lit
textures agree within a few levels): road 50-57 (53), bands 211, dashes 140, field 127,
the sunlit wall 24 and a wall in shade 2. The sky is never drawn by DeepRacer: above a
wall's top the camera sees the renderer's background, SDF's default grey (0.7, 0.7, 0.7).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

# Greyscale tones (0..255) of the lit scene.
ROAD = 53
BORDER = 211  # the white bands along both road edges
CENTRE = 140  # orange dashes
GRASS = 127  # the green field around the road
BACKGROUND = 179  # 0.7 grey: what a ray passing over a wall meets
# Walls by the way they face. The sun's light falls along (-0.5, 0.1, -0.9): the wall on
# the field's low-x side faces it squarely (24), the high-y wall catches a fifth of that
# (6), the other two stand in shade.
WALL_LOW_X = 24
WALL_HIGH_X = 2
WALL_LOW_Y = 2
WALL_HIGH_Y = 6
# Ground cells beyond the walls carry this value; the camera replaces it with the tone of
# the wall in front of them by taking the larger of the two, so every tone on the ground
# stays above GROUND_FLOOR, brighter than any wall.
BEYOND_WALLS = 0
GROUND_FLOOR = max(WALL_LOW_X, WALL_HIGH_X, WALL_LOW_Y, WALL_HIGH_Y) + 1

# Solid objects standing on the track (`sim.sensors.camera.Solids`), drawn as upright boxes in
# flat tones: their sides in one tone, their top in a slightly lighter one, so the edge
# between the two shows wherever a camera looks down on an object. The tones are
# racer-tui's choice, not read off DeepRacer frames: what a model needs is that an object
# never blends into what lies around it, so each tone keeps more than four grain spreads
# (ROAD_GRAIN, GRASS_GRAIN) from the road and the field and well away from the bands.
# * DeepRacer's box_obstacle, a cardboard box 0.4 m long, 0.3 m wide and 0.25 m tall, in a
#   mid grey-brown: lighter than the road, darker than the field and the dashes.
# * A bot car in head-to-bot racing, DeepRacer's car body (0.3235 m long, 0.1961 m wide,
#   about 0.16 m tall), in a dark grey: darker than the road, a little brighter than the
#   walls.
# DeepRacer's camera, 0.127 m up, is lower than either object's top, so it sees their
# sides only; a higher camera sees the tops too.
BOX_SIDE = 96
BOX_TOP = 112
BOT_CAR_SIDE = 30
BOT_CAR_TOP = 36

# Grain: the spread (standard deviation, grey levels) of the textures at racer-tui's 1 cm
# cells, between what DeepRacer's 160x120 frame shows near the car (road 4.8, field 2)
# and a few metres ahead (2.5).
ROAD_GRAIN = 4.0
GRASS_GRAIN = 2.0
BORDER_GRAIN = 4.0

# Paint, in metres.
BORDER_BAND_WIDTH = 0.0762  # inside the road, from each border inwards
DASH_LENGTH = 0.0508
DASH_GAP = 0.0508
DASH_WIDTH = 0.0254
FIELD_MARGIN = 0.91  # from the road's bounding box to the walls
WALL_HEIGHT = 1.0

# Grain comes in tiles of GRAIN_TILE cells (2.56 m at 1 cm) repeated across the ground:
# no pattern a camera notices, and no full-size random field to draw for a large track.
GRAIN_TILE = 256
_GRAIN_SEED = 2018


def grainy_tile(tone: int, spread: float, seed: int) -> NDArray[np.uint8]:
    """A square tile of `tone` with fixed grain of standard deviation `spread`, kept in
    GROUND_FLOOR..255; the same every time for the same arguments."""
    rng = np.random.default_rng([_GRAIN_SEED, seed])
    noise = rng.normal(0.0, spread, size=(GRAIN_TILE, GRAIN_TILE))
    return np.clip(np.rint(tone + noise), GROUND_FLOOR, 255).astype(np.uint8)
