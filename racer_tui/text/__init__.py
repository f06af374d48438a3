"""Renderings both front ends show: a reward map and a reward lap as text (rich), used by
the command line and the app's model editor alike."""
