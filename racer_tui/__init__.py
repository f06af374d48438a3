"""racer-tui front ends: the command line (headless) and the Textual app."""
