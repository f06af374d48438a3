"""A racer's `sync --push` in its own OS process, through the engine, for the tests that
run two pushes at once or kill one halfway.

    python -m tests.league.sync.sync_worker DB STORE_URL BATCH [STOP_AFTER]

Prints "ready" and waits for one line on stdin (so a test can start two pushes together),
then pushes in batches of BATCH, printing "sent N of T" as the store takes records, and
finally the summary as one JSON line. With STOP_AFTER it prints "stopped" once that many
records are sent and blocks, mid-batch, until the test kills it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from league.opening import open_league
from league.sync.engine import push, store_key
from league.sync.retry import RetryPolicy
from league.sync.stores import open_store


def main(db: Path, url: str, batch: int, stop_after: int | None) -> None:
    with (
        open_league(db) as league,
        open_store(url, retry=RetryPolicy(max_attempts=4, base_delay_s=0.02)) as store,
    ):
        print("ready", flush=True)
        sys.stdin.readline()

        def report(direction: str, done: int, total: int | None) -> None:
            print(f"sent {done} of {total}", flush=True)
            if stop_after is not None and done >= stop_after:
                print("stopped", flush=True)
                sys.stdin.readline()  # blocks: the test kills this process now

        summary = push(league, store, store_key(url), progress=report, batch=batch)
    print(json.dumps(summary.to_json()), flush=True)


if __name__ == "__main__":
    stop = int(sys.argv[4]) if len(sys.argv) > 4 else None
    main(Path(sys.argv[1]), sys.argv[2], int(sys.argv[3]), stop)
