"""SIGKILL racer-tui where it writes, and count what is lost or corrupt afterwards.

    python -m benchmarks.app.kill [--sync-kills 50] [--train-kills 50] [--writers 8]
                                   [--records 2000] [--json]

Each part runs the real commands as child processes, in a temporary data directory:

- push: a league of `--records` submissions pushes to a fresh shared-folder store with
  `racer-tui sync --push`; it is killed at a random moment, then pushed again to the end.
  The store must then hold exactly the league's records (same keys, same content), each
  once; the league must know it (nothing left to push).
- pull: a fresh league pulls that store with `racer-tui sync --pull`, killed at a random
  moment, then pulls again: it must hold exactly the store's records, none twice.
- writers: `--writers` processes record races into one league at once; every race must
  be there, and the database must pass SQLite's integrity check.
- train: `racer-tui train` runs, and its training child (the process that writes the
  checkpoints) is killed at a random moment after it starts; the model folder must open,
  every JSON, YAML and weights file in it must read, every next training must start from
  the last checkpoint once there is one, and at the end one more must resume and finish.

Figures are printed, never judged here; tests/benchmarks/test_kill.py runs a small
scale and checks them.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Final

from sim.foundation.home import home_at

_KILL_WINDOW_S: Final = 4.0  # a push or pull of the default league takes about this long
# After the training child starts: it writes a checkpoint every 10 s of training, so kills
# land before the first, around the first and second writes, and between them.
_TRAIN_WINDOW_S: Final = (0.5, 25.0)
_LAST_TRAINING_MINUTES: Final = 0.1  # the training after the kills, resumed to its end


@dataclass
class Part:
    runs: int = 0
    killed_mid_way: int = 0  # the process was still running when it was killed
    lost: int = 0
    duplicated: int = 0
    corrupt: int = 0
    resumed: int = 0  # trainings that started from the last checkpoint
    problems: list[str] = field(default_factory=list)


def _cli(*args: str) -> subprocess.Popen[bytes]:
    """A racer-tui command in the scratch data directory (inherited from `run`)."""
    return subprocess.Popen(
        [sys.executable, "-m", "racer_tui.cli.main", *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def _kill_after(process: subprocess.Popen[bytes], seconds: float) -> bool:
    """SIGKILL `process` after `seconds`; True if it was still running then."""
    try:
        process.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        return True
    return False


def _run(*args: str) -> None:
    process = _cli(*args)
    if process.wait(timeout=600) != 0:
        raise RuntimeError(f"racer-tui {' '.join(args)} failed (exit {process.returncode})")


# --- push and pull --------------------------------------------------------------------------


def _store_records(url: str) -> tuple[dict[tuple[str, str], str], int]:
    """The store's records (key -> content hash) and how many files it holds for them."""
    from league.sync.record import SyncRecord
    from league.sync.stores import open_store

    held: dict[tuple[str, str], str] = {}
    count = 0
    with open_store(url) as store:
        cursor = None
        while True:
            page = store.pull(cursor, limit=1000)
            for record in page.records:
                assert isinstance(record, SyncRecord)
                count += 1
                held[record.key] = record.content_hash
            cursor = page.next_cursor
            if not page.more:
                return held, count


def _league_records(db: Path) -> dict[tuple[str, str], str]:
    from league.opening import open_league
    from league.sync.outgoing import unsent_batches

    with open_league(db) as league:
        return {
            record.key: record.content_hash
            for batch in unsent_batches(league, "nowhere")
            for record in batch.records
        }


def _compare(
    part: Part, expected: dict[tuple[str, str], str], got: dict[tuple[str, str], str]
) -> None:
    part.lost += len(set(expected) - set(got))
    part.corrupt += sum(1 for key in set(expected) & set(got) if expected[key] != got[key])


def push_kills(root: Path, kills: int, records: int, rng: random.Random) -> Part:
    from benchmarks.league.board import fill
    from league.opening import open_league
    from league.sync.engine import store_key
    from league.sync.outgoing import count_unsent
    from league.sync.stores import open_store
    from league.trust.keys import load_or_create_key
    from league.trust.membership import found_league

    source = root / "source.db"
    with open_league(source) as league:
        fill(
            league,
            racers=50,
            submissions=records,
            laps_per_submission=3,
            tracks=2,
            nights=1,
            racers_per_night=5,
        )
        found_league(league, load_or_create_key())  # the organiser's league
    part = Part()
    for run in range(kills):
        url = f"dir:{root / f'push-store-{run}'}"
        with open_store(url) as store:
            store.init()  # `sync init` would push the whole league itself: set up only
        pusher = _cli("sync", "--push", "--store", url, "--db", str(source))
        part.killed_mid_way += _kill_after(pusher, rng.uniform(0.0, _KILL_WINDOW_S))
        _run("sync", "--push", "--store", url, "--db", str(source))
        expected = _league_records(source)
        held, files = _store_records(url)
        _compare(part, expected, held)
        part.duplicated += files - len(held)
        with open_league(source) as league:
            if count_unsent(league, store_key(url)):
                part.problems.append(f"push {run}: the league still has records to push")
        part.runs += 1
        if run < kills - 1:
            shutil.rmtree(root / f"push-store-{run}")
    return part


def pull_kills(root: Path, kills: int, rng: random.Random) -> Part:
    stores = sorted(root.glob("push-store-*"))
    url = f"dir:{stores[-1]}"
    expected, _ = _store_records(url)
    part = Part()
    for run in range(kills):
        db = root / f"puller-{run}.db"
        puller = _cli("sync", "--pull", "--store", url, "--db", str(db))
        part.killed_mid_way += _kill_after(puller, rng.uniform(0.0, _KILL_WINDOW_S))
        _run("sync", "--pull", "--store", url, "--db", str(db))
        got = _league_records(db)
        _compare(part, expected, got)
        part.duplicated += max(0, len(got) - len(expected))
        part.runs += 1
        db.unlink()
    return part


# --- concurrent writers ---------------------------------------------------------------------

_WRITER: Final = """
import sys
from dataclasses import replace
from league.races import record_race
from league.opening import open_league
from sim.foundation.ids import new_id
from sim.race.driver import reference_driver
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track

db, racer, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
track = resolve_track("hairpin-circuit")
result = run_race(track, RaceRules(window_seconds=20.0), reference_driver(track), racer=racer)
sys.stdout.write("ready\\n")
sys.stdout.flush()
sys.stdin.readline()
with open_league(db) as league:
    for _ in range(count):
        record_race(league, replace(result, result_id=new_id()))
"""


def concurrent_writers(root: Path, writers: int, races_each: int) -> Part:
    from league.opening import open_league

    db = root / "writers.db"
    with open_league(db):
        pass  # created and migrated once, before the writers race each other
    processes = [
        subprocess.Popen(
            [sys.executable, "-c", _WRITER, str(db), f"writer-{n}", str(races_each)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        for n in range(writers)
    ]
    for process in processes:
        assert process.stdout is not None
        process.stdout.readline()  # each has its race ready: they all write at once
    for process in processes:
        assert process.stdin is not None
        process.stdin.write("go\n")
        process.stdin.flush()
    part = Part(runs=writers)
    for process in processes:
        if process.wait(timeout=600) != 0:
            part.problems.append(f"a writer failed (exit {process.returncode})")
    with open_league(db) as league:
        races = len(league.query("SELECT id FROM races"))
        check = str(league.conn.execute("PRAGMA integrity_check").fetchone()[0])
    part.lost = writers * races_each - races
    part.corrupt = 0 if check == "ok" else 1
    return part


# --- training -------------------------------------------------------------------------------


def train_kills(
    kills: int,
    rng: random.Random,
    window: tuple[float, float] = _TRAIN_WINDOW_S,
    last_minutes: float = _LAST_TRAINING_MINUTES,
) -> Part:
    from sim.garage.options import new_model
    from sim.training import events

    folder = new_model("kill-target")
    part = Part()
    for _ in range(kills):
        command = [sys.executable, "-m", "racer_tui.cli.main", "train", folder.name, "--json"]
        command += ["--minutes", "1"]
        cli = subprocess.Popen(
            command,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        assert cli.stdout is not None
        child = 0
        had_checkpoint = (folder.checkpoints_dir / "latest.safetensors").is_file()
        for line in cli.stdout:
            event = events.decode(line)
            if isinstance(event, events.Started):
                child = event.pid
                if had_checkpoint and event.resumed_from != "checkpoint":
                    part.problems.append(f"a training started from {event.resumed_from}")
                part.resumed += event.resumed_from == "checkpoint"
                break
        if child:
            time.sleep(rng.uniform(*window))
            try:
                os.kill(child, signal.SIGKILL)
                part.killed_mid_way += 1
            except ProcessLookupError:
                pass
        cli.wait(timeout=120)
        part.runs += 1
        part.corrupt += _corrupt_files(folder.name, part.problems)
    before = _steps(folder.name)
    last = subprocess.run(
        [
            sys.executable,
            "-m",
            "racer_tui.cli.main",
            "train",
            folder.name,
            "--minutes",
            str(last_minutes),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    stream = [events.decode(line) for line in last.stdout.splitlines() if line.strip()]
    started = next((e for e in stream if isinstance(e, events.Started)), None)
    if not stream or events.type_of(stream[-1]) != "finished":
        part.problems.append(f"the training after the kills did not finish: {last.stderr[-300:]}")
    elif before and (started is None or started.resumed_from != "checkpoint"):
        part.problems.append("the training after the kills did not resume from its checkpoint")
    return part


def _steps(name: str) -> int:
    from sim.garage.folder import open_model

    state = open_model(name).training_state() or {}
    steps = state.get("total_steps", 0)
    return int(steps) if isinstance(steps, int) else 0


def _corrupt_files(name: str, problems: list[str]) -> int:
    """Files of the model folder that do not read (a write cut short and left in place)."""
    import yaml
    from safetensors.numpy import load_file

    from sim.garage.folder import ModelError, open_model

    try:
        folder = open_model(name)
        folder.metadata()
        folder.training_state()
    except (ModelError, ValueError, OSError) as error:
        problems.append(f"the model folder does not open: {error}")
        return 1
    bad = 0
    for path in folder.path.rglob("*"):
        if not path.is_file() or path.name.startswith("."):
            continue  # a temporary file is never read as the real one
        try:
            if path.suffix == ".json":
                json.loads(path.read_text(encoding="utf-8"))
            elif path.suffix in (".yaml", ".yml"):
                yaml.safe_load(path.read_text(encoding="utf-8"))
            elif path.suffix == ".safetensors":
                load_file(path)
        except (ValueError, OSError, yaml.YAMLError) as error:
            bad += 1
            problems.append(f"{path.relative_to(folder.path)} does not read: {error}")
    return bad


# --- the run --------------------------------------------------------------------------------


def run(args: argparse.Namespace) -> dict[str, Any]:
    rng = random.Random(args.seed)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="racer-tui-kill-") as tmp:
        root = Path(tmp)
        parts: dict[str, Part] = {}
        with home_at(root / "home"):  # every command below runs in this scratch home
            if args.sync_kills:
                parts["push"] = push_kills(root, args.sync_kills, args.records, rng)
                parts["pull"] = pull_kills(root, args.sync_kills, rng)
            if args.writers:
                parts["writers"] = concurrent_writers(root, args.writers, args.races_each)
            if args.train_kills:
                window = (_TRAIN_WINDOW_S[0], args.train_window)
                parts["train"] = train_kills(args.train_kills, rng, window, args.last_minutes)
    return {
        "seconds": round(time.perf_counter() - started, 1),
        "parts": {name: asdict(part) for name, part in parts.items()},
        "lost": sum(part.lost for part in parts.values()),
        "duplicated": sum(part.duplicated for part in parts.values()),
        "corrupt": sum(part.corrupt for part in parts.values()),
        "problems": [problem for part in parts.values() for problem in part.problems],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.app.kill", description=__doc__)
    parser.add_argument("--sync-kills", type=int, default=50, help="kills of push, and of pull")
    parser.add_argument("--train-kills", type=int, default=50)
    parser.add_argument(
        "--train-window",
        type=float,
        default=_TRAIN_WINDOW_S[1],
        help="kill a training at most this many seconds after it starts",
    )
    parser.add_argument(
        "--last-minutes",
        type=float,
        default=_LAST_TRAINING_MINUTES,
        help="the budget of the training that resumes after the kills and must finish",
    )
    parser.add_argument("--writers", type=int, default=8, help="processes recording at once")
    parser.add_argument("--races-each", type=int, default=25)
    parser.add_argument("--records", type=int, default=2000, help="submissions in the league")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    report = run(args)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"kill figures in {report['seconds']} s")
    print(
        f"{'part':<8} {'runs':>5} {'killed mid-way':>15} {'lost':>5} {'twice':>6} "
        f"{'corrupt':>8} {'resumed':>8}"
    )
    for name, part in report["parts"].items():
        print(
            f"{name:<8} {part['runs']:>5} {part['killed_mid_way']:>15} {part['lost']:>5} "
            f"{part['duplicated']:>6} {part['corrupt']:>8} {part['resumed']:>8}"
        )
    for problem in report["problems"]:
        print(f"  {problem}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
