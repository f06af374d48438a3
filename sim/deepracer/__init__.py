"""DeepRacer's vocabulary and files: the model folder's files (metadata, hyperparameters,
sim-traces, metrics, checkpoints) read and written byte for byte as simapp and
deepracer-for-cloud write them, and the action space.

Stands on `sim.foundation`; the one home racer-tui's other floors take DeepRacer's names
and formats from."""
