"""A racer's push in its own OS process, for the concurrent-push tests.

    python -m tests.league.sync.push_worker STORE_URL FIRST_OWN_SERIAL [reverse]

Pushes the shared records (the same ids in every worker) plus its own, after printing
"ready" and reading one line from stdin, so the test can start both pushes together.
With `reverse` it pushes in the opposite order, so two workers meet on the same records
whichever starts first. Prints the push report as one JSON line.
"""

from __future__ import annotations

import json
import sys

from league.sync.retry import RetryPolicy
from league.sync.stores import open_store
from tests.league.sync.records import submissions

SHARED = 60
OWN = 20


def main(url: str, first_own: int, reverse: bool) -> None:
    records = submissions(SHARED) + submissions(OWN, start=first_own)
    if reverse:
        records.reverse()
    with open_store(url, retry=RetryPolicy(max_attempts=4, base_delay_s=0.02)) as store:
        print("ready", flush=True)
        sys.stdin.readline()
        report = store.push(records)
    print(
        json.dumps(
            {
                "pushed": [ref.record_id for ref in report.pushed],
                "skipped": [ref.record_id for ref in report.skipped],
                "conflicts": [conflict.record_id for conflict in report.conflicts],
            }
        ),
        flush=True,
    )


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3:] == ["reverse"])
