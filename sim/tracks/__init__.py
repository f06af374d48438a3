"""Tracks: geometry, a track file read and checked, building tracks from designs, the
catalog with DeepRacer's official names, the built-in designs and the generator.

Stands on `sim.foundation` and the `tracks` data package; knows nothing of the car, the
sensors or rewards."""
