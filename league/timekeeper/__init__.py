"""The timekeeper of a physical car's heat: the race clock, the laps captured by hand (or by
an automatic timer's lap triggers) and the car resets, turned into a league result like any
simulated heat's.

AWS's DeepRacer Event Manager is the model: a race clock and a lap clock that start and
pause together, Capture Lap, Car Reset counted against the lap in progress (a lap with more
resets than the rules allow does not count), undo of a false finish or a reset too many,
did-not-finish, and a race that ends at the first capture after its time is up (the lap in
progress when the clock reaches zero may still be finished). `heat` is the state machine;
`match` times two physical cars of a bracket match at once; `journal` keeps either's
inputs so a stopped racer-tui resumes it; `feed` reads an automatic timer's lines.
"""
