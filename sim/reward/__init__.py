"""Rewards: a racer's reward function loaded and called with DeepRacer's params, and the
fence around it (its own process session with time and memory limits, landlock where the
kernel has it); the sample params, the probe, the reward map and lap, and the templates.

Stands on `sim.foundation`, `sim.tracks`, `sim.physics` and `sim.sensors`."""
