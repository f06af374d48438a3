"""Sensors: what a car perceives. The camera and its scene (DeepRacer's tones and
walls), the top-down raster every sensor reads, the lidar and the camera for many cars at
once (`batched`), and the observations a policy is given.

Stands on `sim.foundation`, `sim.tracks` and `sim.physics`."""
