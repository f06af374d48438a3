"""Training benchmarks: how fast fresh models learn to lap (alone, among objects, with the
racing line) and how training scales across processes; `runs` is what they share."""
