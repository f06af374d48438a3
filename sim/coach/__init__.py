"""The coach: the fastest lap a car can drive on a track, and where a model loses time.

- `limits`: what the simulated car can do (top speed, grip, acceleration, braking, the
  tightest turn at each speed), for racer-tui's car or a model's action space.
- `speed_profile`: the fastest speeds along a line under those limits, and its lap times
  (flying, and from a standing start).
- `racing_line`: a minimum-time line inside the track's borders.
- `limit_lap`: the two together for a track, cached by the track's content.
- `tracking`: the simulator driven along a limit lap, to check that it can be driven.
- `lap_floor`: the fastest lap any DeepRacer car could drive on a track under DeepRacer's
  rules, the floor under which a league accepts no lap (`sim.coach.plausible`).

No Textual, no torch: the command line and the app both read these.
"""
