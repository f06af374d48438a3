"""League benchmarks: a big league's queries, sync through each store, the fuzzed doors
untrusted input comes through, and the attacks a league's trust must hold against."""
