"""The simulation's benchmarks: env steps per second, a 4-minute race per driver, the
limit lap, reward maps, calibration against DeepRacer's sim-traces, and sim-to-real."""
