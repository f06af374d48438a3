"""Training, evaluation and the policy network of racer-tui models.

Only the modules that build, train or run a network import torch (`policy`, `ppo`,
`worker`); the event stream, the launcher and evaluation bookkeeping stay light so the
CLI and the TUI can watch a training run without loading torch themselves.
"""
