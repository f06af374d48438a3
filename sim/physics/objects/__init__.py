"""DeepRacer's other two race types, object avoidance and head-to-bot (issue 19, in progress):
their settings as `training_params.yaml` holds them, and where the boxes and bots go.
DeepRacer's own semantics, read in deepracer-simapp, are in docs/deepracer-objects.md."""
