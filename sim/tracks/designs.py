"""The built-in tracks: this project's own circuits, drawn as straights and arcs.

Run `python -m sim.tracks.designs` to (re)write `tracks/<name>.npy` and `tracks/index.yaml`;
the output is deterministic, so a re-run changes no bytes unless a design changed.
Every design turns counter-clockwise and starts half-way along its first straight.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml

import tracks
from sim.foundation.atomic import write_text_atomic
from sim.tracks.builder import Arc, Segment, Straight, build_from_segments
from sim.tracks.track import Track

# DeepRacer's two road widths: the classic 30-inch and the later wide 42-inch tracks.
NARROW = 0.76
WIDE = 1.07
FREE = Straight()
"""A straight whose length the builder chooses so the loop closes (two per design)."""


@dataclass(frozen=True)
class TrackDesign:
    name: str
    description: str
    width: float
    segments: tuple[Segment, ...]
    heading_deg: float = 0.0

    def build(self) -> Track:
        return build_from_segments(
            self.name,
            self.segments,
            width=self.width,
            description=self.description,
            heading_deg=self.heading_deg,
        )


def _pocket(entry_radius: float, leg: float, hairpin_radius: float) -> tuple[Segment, ...]:
    """A dip into the infield ending in a right-hand hairpin; it turns 0 degrees net."""
    return (
        Arc(entry_radius, 90),
        Straight(leg),
        Arc(hairpin_radius, -180),
        Straight(leg),
        Arc(entry_radius, 90),
    )


def _chicane(
    outer_radius: float, apex_radius: float, swing_deg: float, net_deg: float = 0.0
) -> tuple[Segment, ...]:
    """Left-right-left: swing out, cut back through the apex, swing out again; turns `net_deg`."""
    apex = Arc(apex_radius, net_deg - 2 * swing_deg)
    return (Arc(outer_radius, swing_deg), apex, Arc(outer_radius, swing_deg))


BEGINNER_OVAL = TrackDesign(
    name="beginner-oval",
    description=(
        "A wide egg-shaped oval with one gentle and one tighter end: the first track to learn on."
    ),
    width=WIDE,
    heading_deg=-5,
    segments=(FREE, Arc(1.8, 190), FREE, Arc(1.3, 170)),
)

HAIRPIN_CIRCUIT = TrackDesign(
    name="hairpin-circuit",
    description="A compact technical circuit whose two infield pockets end in 0.55 m hairpins.",
    width=NARROW,
    segments=(
        Straight(1.9),
        Arc(0.6, 90),
        FREE,
        Arc(0.6, 90),
        *_pocket(0.6, 0.0, 0.55),
        Straight(1.9),
        Arc(0.6, 90),
        Straight(1.5),
        Arc(0.6, 90),
        FREE,
        *_pocket(0.6, 0.0, 0.55),
    ),
)

BOWTIE_CHICANE = TrackDesign(
    name="bowtie-chicane",
    description="Two round lobes joined at a narrow waist, crossed twice through a tight chicane.",
    width=NARROW,
    heading_deg=-25,
    segments=(
        FREE,
        Arc(1.4, 230),
        FREE,
        *_chicane(0.45, 0.45, 20, -50),
        Straight(1.0),
        Arc(1.4, 230),
        Straight(1.0),
        *_chicane(0.45, 0.45, 20, -50),
    ),
)

SPEEDWAY = TrackDesign(
    name="speedway",
    description="A fast tri-oval of long sweeping turns and a kinked front stretch.",
    width=WIDE,
    heading_deg=-20,
    segments=(
        Straight(2.4),
        Arc(3.0, 40),
        FREE,
        Arc(2.0, 160),
        FREE,
        Arc(2.0, 160),
    ),
)

GRAND_PRIX = TrackDesign(
    name="grand-prix",
    description=(
        "A long circuit: a fast main straight with a bus-stop chicane, esses, a sweeper "
        "and two hairpin pockets."
    ),
    width=NARROW,
    segments=(
        FREE,
        *_chicane(0.8, 0.8, 40),
        Straight(3.0),
        Arc(1.0, 90),
        Straight(1.8),
        Arc(1.2, -40),
        Arc(1.2, 80),
        Arc(1.2, -40),
        Straight(1.8),
        Arc(1.0, 90),
        Straight(3.0),
        *_pocket(0.8, 3.2, 0.6),
        Straight(2.0),
        Arc(2.5, 45),
        FREE,
        Arc(1.5, -40),
        Straight(1.0),
        Arc(1.5, 40),
        Straight(1.0),
        Arc(1.0, 45),
        Straight(1.0),
        Arc(1.2, 90),
        Straight(2.0),
        *_pocket(0.7, 1.6, 0.55),
    ),
)

DESIGNS: tuple[TrackDesign, ...] = (
    BEGINNER_OVAL,
    HAIRPIN_CIRCUIT,
    BOWTIE_CHICANE,
    SPEEDWAY,
    GRAND_PRIX,
)


def index_entry(track: Track, file_name: str) -> dict[str, object]:
    return {
        "name": track.name,
        "file": file_name,
        "description": track.description,
        "length_m": round(track.length, 2),
        "width_m": round(track.width, 3),
        "direction": track.direction,
        "waypoints": len(track.points),
        # The league's identity of the track, so finding a track by hash loads no array.
        "sha256": track.content_hash,
    }


def write_builtin_tracks(
    directory: Path, designs: Sequence[TrackDesign] = DESIGNS
) -> list[dict[str, object]]:
    """Build every design into `directory` (one .npy each plus index.yaml); return the index."""
    entries = []
    for design in designs:
        track = design.build()
        file_name = f"{design.name}.npy"
        track.save(directory / file_name)
        entries.append(index_entry(track, file_name))
    text = yaml.safe_dump(entries, sort_keys=False, allow_unicode=True, width=1000)
    write_text_atomic(directory / "index.yaml", text)
    return entries


def main() -> None:
    directory = Path(tracks.__file__).parent
    for entry in write_builtin_tracks(directory):
        print(
            f"{entry['name']:<16} {entry['length_m']:>6} m  {entry['width_m']} m wide  "
            f"{entry['waypoints']} waypoints"
        )


if __name__ == "__main__":
    main()
