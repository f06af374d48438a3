"""Physics: DeepRacer's car (its kinematics and limits), the simulation step over a
track with its objects, resets after an off-track or a crash, and the reference driver
that follows a line at the car's limits.

Stands on `sim.foundation` and `sim.tracks`."""
