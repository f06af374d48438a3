"""AWS DeepRacer's four sample reward functions, shipped as plain files.

They are data, not modules of this package: `sim.reward_function` reads their text and loads
them exactly like a racer's own file, so a template behaves the same as its copy in a model.
"""
