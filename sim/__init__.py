"""The simulator: tracks, car physics, DeepRacer reward params, sensors, the gymnasium env.

Nothing here imports textual or rich widgets, and torch is imported only by the modules
that train or run a policy, so the headless race path starts fast.
"""
