"""The car export: a trained policy written as the car's archive (`export`: the frozen
graph the physical car loads, with its model_metadata.json), and what the car would do on a
picture (`act`). Above the training, whose policies it writes; the archive's format and its
readers are `sim.car_archive`.
"""
