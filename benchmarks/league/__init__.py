"""League benchmarks: trust in shared results."""
