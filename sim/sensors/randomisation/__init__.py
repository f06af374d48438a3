"""Camera randomisation: training for the real world (issue 22, part 4).

A real car's camera never shows the clean picture racer-tui renders: the light changes,
the sensor is noisy, the lens blurs, the camera sits a little higher or lower and looks a
little up or down, and a home track's road, lines and surroundings are other colours. A
camera model trained with randomisation sees, every episode and for every car, a camera
drawn afresh within bounds, so its policy cannot lean on one exact picture.

* `settings`: what a model asks for (`CameraRandomisation`, one strength per family) and
  how it is kept in `training_params.yaml` (`CAMERA_RANDOMISATION_*` keys; none = off).
* `perturbation`: one drawn camera (`CameraPerturbation`) and the seeded draw.
* `frames`: light, contrast and colours as a per-level lookup, blur and sensor noise on
  rendered frames.
* `render`: `PerturbedCamera`, which renders each car through its own perturbation (the
  pose through the camera's geometry) for `sim.sensors.observations.Observer`.

Evaluations and races keep the plain render; only training draws perturbations.
"""
