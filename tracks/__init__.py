"""Built-in track data (DeepRacer .npy layout) and its YAML index, shipped as package data."""
