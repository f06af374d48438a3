"""Two racers pushing into one store at the same moment, from two OS processes."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

from tests.conftest import REPO_ROOT
from tests.league.sync.conftest import StoreFactory
from tests.league.sync.push_worker import OWN, SHARED
from tests.league.sync.records import keys, submissions
from tests.league.sync.test_store_contract import pull_all


def _start_worker(url: str, first_own: int, *options: str) -> subprocess.Popen[str]:
    worker = subprocess.Popen(
        [sys.executable, "-m", "tests.league.sync.push_worker", url, str(first_own), *options],
        cwd=REPO_ROOT,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert worker.stdout is not None
    assert worker.stdout.readline().strip() == "ready"  # waits for the process, no sleep
    return worker


def _finish(worker: subprocess.Popen[str]) -> dict[str, Any]:
    out, _ = worker.communicate(timeout=120)
    assert worker.returncode == 0
    return dict(json.loads(out.strip().splitlines()[-1]))


def test_concurrent_pushes_from_two_processes_store_each_record_once(
    store_url: str, store_kind: str, open_racer_store: StoreFactory
) -> None:
    first, second = _start_worker(store_url, 1000), _start_worker(store_url, 2000, "reverse")
    for worker in (first, second):
        assert worker.stdin is not None
        worker.stdin.write("go\n")
        worker.stdin.flush()
    reports = [_finish(first), _finish(second)]

    assert all(report["conflicts"] == [] for report in reports)
    shared_ids = {record.record_id for record in submissions(SHARED)}
    for report in reports:
        assert len(report["pushed"]) + len(report["skipped"]) == SHARED + OWN
    pushed_shared = [rid for report in reports for rid in report["pushed"] if rid in shared_ids]
    if store_kind == "dir":
        # os.link is an atomic create-only publish: exactly one racer wins each record.
        assert sorted(pushed_shared) == sorted(shared_ids)
    else:
        # moto's server checks the put condition without a lock, so two simultaneous puts
        # of the same (identical) record can both report "pushed"; DynamoDB itself cannot.
        assert set(pushed_shared) == shared_ids

    expected = submissions(SHARED) + submissions(OWN, start=1000) + submissions(OWN, start=2000)
    pulled = pull_all(open_racer_store())
    assert keys(pulled.records) == keys(expected)
    assert pulled.quarantined == []
