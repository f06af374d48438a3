"""The app's benchmarks: start-up, the race view's drawing, the timekeeper's keys under
load, a soak beside a training, SIGKILL where the app writes, and the long monkey."""
