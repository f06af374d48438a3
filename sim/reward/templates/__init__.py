"""The reward templates a racer can start from, written for racer-tui: each pays what the
DeepRacer console's template of the same name pays (the same thresholds and the same
rewards), in its own code, with a docstring saying what it teaches and where it stops.

They are data, not modules of this package: `sim.reward.function` reads their text and
loads them exactly like a racer's own file, so a template behaves the same as its copy in a
model. Each file stands alone (a racer copies it into their model folder and edits it).
"""
