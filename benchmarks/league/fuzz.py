"""Fuzz every door untrusted input comes through, and count what gets past.

    python -m benchmarks.league.fuzz [--cases 10000] [--seed 1] [--json]

Five families, each fed to the same function the app and the commands use:

- record: league records as a store holds them (envelope bytes), mutated from a real,
  signed league: truncated, bytes flipped, fields of the wrong type, huge or deeply
  nested bodies, markup and terminal escapes in names, content changed with the seal
  kept, re-signed by a stranger, unsigned, wrong kinds and ids. Decoded, checked and
  applied as a pull does (league.sync.incoming) into a scratch league.
- rules: rules files (YAML) with wrong types, out-of-range numbers, duplicate keys,
  Python tags, random bytes (sim.race.rules.load_rules).
- track: DeepRacer .npy track files with NaN, wrong shapes, pickled objects, too many
  points, truncated or random bytes (sim.tracks.track.load_track).
- reward: values a reward function returns: any type and size (a RewardFunction call).
- bundle: .racer-bundle files truncated, with `../` paths, zip bombs, pickles, broken
  manifests (sim.garage.bundle.read_bundle).

Each case ends as *refused* (the input's own one-sentence error, or a quarantine entry),
*accepted* (it was valid after all), or a *traceback* (any other exception: a defect).
Afterwards the scratch league must pass SQLite's integrity check with every shared row
still matching its content hash (no partial writes), and the marker file that fuzzed
"code" would create must not exist (nothing was executed). Figures are printed, never
judged here; tests/benchmarks/test_fuzz.py runs a small scale and checks them.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import random
import tempfile
import time
import traceback
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np

from league.errors import LeagueError
from league.opening import open_league
from league.store import League
from league.sync.errors import RecordInvalidError
from league.sync.record import Quarantined, decode_envelope, encode_envelope, make_record
from sim.foundation.home import home_at
from sim.foundation.ids import canonical_json

FAMILIES: Final = ("record", "rules", "track", "reward", "bundle")
MARKER_NAME: Final = "fuzz-executed"
_SHOWN_TRACEBACKS: Final = 5


@dataclass
class Tally:
    cases: int = 0
    refused: int = 0
    accepted: int = 0
    tracebacks: int = 0
    examples: list[str] = field(default_factory=list)  # the first few tracebacks


@dataclass
class Scratch:
    """Everything the cases are fed into, made once per run in a temporary folder."""

    root: Path
    rng: random.Random
    marker: Path
    target: League
    envelopes: list[bytes]
    organiser: Any  # league.trust.keys.SigningKey
    track_rows: np.ndarray
    bundle: bytes


# --- random values --------------------------------------------------------------------------


def _nasty_text(rng: random.Random, marker: Path) -> str:
    return rng.choice(
        [
            "[bold red]x[/]",
            "\x1b[2J\x1b[31mred",
            "ana\u202egnp.exe",
            "a\u200bna",
            "аna",  # Cyrillic a
            "",
            " ",
            "x" * rng.choice([101, 5000, 40_000]),
            f"__import__('os').system('touch {marker}')",
            "\ud800",
            "\x00",
            "🏎" * 30,
        ]
    )


def _value(rng: random.Random, marker: Path, depth: int = 0) -> Any:
    choice = rng.randrange(12 if depth < 3 else 9)
    if choice == 0:
        return None
    if choice == 1:
        return rng.choice([True, False])
    if choice == 2:
        return rng.choice([0, -1, 1, 2**31, 2**63, 2**70, -(2**64)])
    if choice == 3:
        return rng.choice([0.0, -0.0, 1e308, -1e-308, 3.5, 1e-9, 123456789.123])
    if choice in (4, 5, 6):
        return _nasty_text(rng, marker)
    if choice in (7, 8):
        return rng.choice(["2026-11-24T20:00:00.000Z", "1970-01-01T00:00:00Z", "not a time"])
    if choice in (9, 10):
        return [_value(rng, marker, depth + 1) for _ in range(rng.randrange(4))]
    return {f"k{n}": _value(rng, marker, depth + 1) for n in range(rng.randrange(4))}


_DEEP: Final = "<deeply nested list>"


# --- the scratch world ----------------------------------------------------------------------


def _make_scratch(root: Path, seed: int) -> Scratch:
    from league.races import record_race
    from league.seasons import new_season
    from league.sync import incoming
    from league.sync.outgoing import unsent_batches
    from league.trust.keys import SigningKey
    from league.trust.membership import found_league
    from league.trust.seals import make_seal
    from sim.race.driver import reference_driver
    from sim.race.engine import run_race
    from sim.race.rules import RaceRules
    from sim.tracks.catalog import find_track_info, resolve_track

    organiser = SigningKey.generate()
    with open_league(root / "source.db") as source:
        found_league(source, organiser)
        track = resolve_track("hairpin-circuit")
        result = run_race(track, RaceRules(window_seconds=30.0), reference_driver(track), seed=3)
        record_race(source, result)
        new_season(source, "fuzz season")
        records = [r for batch in unsent_batches(source, "nowhere") for r in batch.records]
    sealed = [record.sealed(make_seal(record, organiser)) for record in records]
    target = open_league(root / "target.db")
    founding = [record for record in sealed if record.kind == "roster"]
    with target.transaction():
        incoming.apply_page(target, "fuzz", founding)  # the target knows its organiser
    rows = np.load(find_track_info("reinvent_base").path, allow_pickle=False)
    return Scratch(
        root=root,
        rng=random.Random(seed),
        marker=root / MARKER_NAME,
        target=target,
        envelopes=[encode_envelope(record) for record in sealed],
        organiser=organiser,
        track_rows=np.asarray(rows, dtype=np.float64),
        bundle=_base_bundle(root),
    )


def _base_bundle(root: Path) -> bytes:
    from safetensors.numpy import save

    from sim.garage.bundle import export_bundle
    from sim.garage.options import new_model

    folder = new_model("fuzz-car")
    rng = np.random.default_rng(0)
    tensors = {
        "policy.0.weight": rng.standard_normal((8, 21)).astype(np.float32),
        "policy.0.bias": np.zeros(8, dtype=np.float32),
    }
    folder.policy_file.write_bytes(bytes(save(tensors, metadata={"format": "racer-tui-policy/1"})))
    return export_bundle(folder, root / "base.racer-bundle").read_bytes()


# --- the families ---------------------------------------------------------------------------


def _record_case(scratch: Scratch) -> bool:
    """True when the mutated record was accepted by a pull, False when refused."""
    from league.sync import incoming
    from league.trust.keys import SigningKey
    from league.trust.seals import make_seal

    rng = scratch.rng
    raw = rng.choice(scratch.envelopes)
    mutation = rng.randrange(12)
    if mutation == 0:
        raw = raw[: rng.randrange(len(raw))]
    elif mutation == 1:
        data = bytearray(raw)
        for _ in range(rng.randrange(1, 6)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        raw = bytes(data)
    elif mutation == 11:
        raw = rng.choice([os.urandom(rng.randrange(1, 400)), b"{}", b"[]", b"null", b'"x"'])
    else:
        envelope = json.loads(raw)
        body = envelope["body"]
        if mutation in (2, 3, 4, 5):  # one field of the wrong type or value
            if body:
                body[rng.choice(sorted(body))] = _value(rng, scratch.marker)
        elif mutation == 6:
            body[rng.choice(sorted(body))] = "y" * 300_000
        elif mutation == 7:  # spliced in as text below: too deep for json.dumps
            body[rng.choice(sorted(body))] = _DEEP
        elif mutation == 8:
            envelope[rng.choice(["kind", "id", "version", "format", "content_hash"])] = _value(
                rng, scratch.marker
            )
        elif mutation == 9:
            envelope["signer"] = envelope["signature"] = None
        elif mutation == 10:
            envelope["signature"] = "ab" * 64
        if mutation in (3, 4, 5, 6, 7, 9, 10) or (mutation == 2 and rng.random() < 0.5):
            try:
                record = make_record(envelope["kind"], envelope["id"], body, envelope["version"])
            except (RecordInvalidError, ValueError, TypeError, RecursionError):
                record = None
            if record is not None:
                envelope["content_hash"] = record.content_hash
                if mutation in (4, 5, 6, 7):  # re-signed: by the organiser, or a stranger
                    key = scratch.organiser if mutation != 5 else SigningKey.generate()
                    seal = make_seal(record, key)
                    envelope["signer"], envelope["signature"] = seal.signer, seal.signature
        try:
            raw = canonical_json(envelope)
        except ValueError:
            raw = json.dumps(envelope, default=str).encode("utf-8", "surrogatepass")
        levels = rng.choice([20, 200, 5000])
        raw = raw.replace(json.dumps(_DEEP).encode(), b"[" * levels + b"1" + b"]" * levels)
    decoded = decode_envelope(raw, "fuzz")
    if isinstance(decoded, Quarantined):
        return False
    records, refused = incoming.check_page([decoded])
    if refused:
        return False
    with scratch.target.transaction():
        result = incoming.apply_page(scratch.target, "fuzz", records)
    return not result.held


def _rules_case(scratch: Scratch) -> bool:
    from sim.race.rules import RulesError, load_rules

    rng = scratch.rng
    keys = ["window_seconds", "max_offtracks_per_lap", "penalty_seconds", "ranking", "laps"]
    kind = rng.randrange(5)
    if kind == 0:
        data = os.urandom(rng.randrange(1, 300))
    elif kind == 1:
        data = f"!!python/object/apply:os.system ['touch {scratch.marker}']\n".encode()
    elif kind == 2:
        data = b"window_seconds: 60\nwindow_seconds: 240\n"
    elif kind == 3:
        data = (b"a: &x [" * 30) + b"1" + (b"]" * 30)
    else:
        text = "\n".join(
            f"{rng.choice(keys)}: {json.dumps(_value(rng, scratch.marker), default=str)}"
            for _ in range(rng.randrange(1, 5))
        )
        data = text.encode("utf-8", "surrogatepass")
    path = scratch.root / "rules.yaml"
    path.write_bytes(data)
    try:
        load_rules(path)
    except RulesError:
        return False
    return True


def _track_case(scratch: Scratch) -> bool:
    from sim.tracks.errors import TrackError
    from sim.tracks.track import load_track

    rng = scratch.rng
    rows = scratch.track_rows.copy()
    path = scratch.root / "fuzz-track.npy"
    kind = rng.randrange(8)
    if kind == 0:
        rows[rng.randrange(len(rows)), rng.randrange(6)] = rng.choice([np.nan, np.inf])
        np.save(path, rows)
    elif kind == 1:
        np.save(path, rows[:, : rng.choice([2, 4, 5])])
    elif kind == 2:
        np.save(path, np.array([{"x": 1}, "touch"], dtype=object), allow_pickle=True)
    elif kind == 3:
        np.save(path, np.repeat(rows, rng.choice([20, 40]), axis=0))
    elif kind == 4:
        buffer = io.BytesIO()
        np.save(buffer, rows)
        data = buffer.getvalue()
        path.write_bytes(data[: rng.randrange(len(data))])
    elif kind == 5:
        path.write_bytes(os.urandom(rng.randrange(1, 2000)))
    elif kind == 6:
        np.save(path, rows * rng.choice([0.0, 1e6, -1.0, 1e-6]))
    else:
        np.save(path, rows[: rng.randrange(0, 6)])
    try:
        load_track(path)
    except TrackError:
        return False
    return True


_REWARD_SOURCE: Final = "def reward_function(params):\n    return params['value']\n"


def _reward_case(scratch: Scratch) -> bool:
    from decimal import Decimal
    from fractions import Fraction

    from sim.reward.errors import RewardFunctionError
    from sim.reward.function import load_reward_source

    rng = scratch.rng
    function = load_reward_source(_REWARD_SOURCE, "fuzz_reward.py")
    value = rng.choice(
        [
            _value(rng, scratch.marker),
            10**400,
            -(10**400),
            complex(1, 2),
            Decimal("1e999"),
            Fraction(1, 3),
            np.float32(np.nan),
            np.float64(2.0),
            np.array([1.0, 2.0]),
            np.array(3.0),
            np.int64(7),
            b"1.0",
            float("inf"),
            float("nan"),
            set(),
        ]
    )
    try:
        function({"value": value})
    except RewardFunctionError:
        return False
    return True


def _bundle_case(scratch: Scratch) -> bool:
    from sim.garage.bundle import read_bundle
    from sim.garage.folder import ModelError

    rng = scratch.rng
    base = scratch.bundle
    path = scratch.root / "fuzz.racer-bundle"
    kind = rng.randrange(7)
    if kind == 0:
        path.write_bytes(base[: rng.randrange(len(base))])
    elif kind == 1:
        flipped = bytearray(base)
        for _ in range(rng.randrange(1, 8)):
            flipped[rng.randrange(len(flipped))] = rng.randrange(256)
        path.write_bytes(bytes(flipped))
    else:
        with zipfile.ZipFile(io.BytesIO(base)) as source:
            members = {info.filename: source.read(info) for info in source.infolist()}
        if kind == 2:
            members["../../escape.txt"] = b"outside"
        elif kind == 3:
            members[rng.choice(sorted(members))] = b"\0" * (64 * 1024 * 1024)  # a bomb
        elif kind == 4:
            members["policy.pkl"] = b"\x80\x04cos\nsystem\n."
        elif kind == 5:
            name = next((n for n in members if n.endswith(".json")), sorted(members)[0])
            members[name] = json.dumps(_value(rng, scratch.marker), default=str).encode()
        else:
            for n in range(rng.choice([2, 300, 3000])):
                members[f"extra/{n}.txt"] = b"x"
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as target:
            for name, data in members.items():
                target.writestr(name, data)
        path.write_bytes(buffer.getvalue())
    try:
        read_bundle(path)
    except ModelError:
        return False
    return True


CASES: Final[dict[str, Callable[[Scratch], bool]]] = {
    "record": _record_case,
    "rules": _rules_case,
    "track": _track_case,
    "reward": _reward_case,
    "bundle": _bundle_case,
}


# --- the run --------------------------------------------------------------------------------


def run(cases: int, seed: int, root: Path) -> dict[str, Any]:
    started = time.perf_counter()
    scratch = _make_scratch(root, seed)
    tallies = {family: Tally() for family in FAMILIES}
    try:
        for number in range(cases):
            family = FAMILIES[number % len(FAMILIES)]
            tally = tallies[family]
            tally.cases += 1
            try:
                accepted = CASES[family](scratch)
            except (LeagueError, RecordInvalidError) as error:  # a clear refusal after all
                del error
                tally.refused += 1
            except Exception:
                tally.tracebacks += 1
                if len(tally.examples) < _SHOWN_TRACEBACKS:
                    tally.examples.append(traceback.format_exc(limit=4)[-1500:])
            else:
                tally.accepted += accepted
                tally.refused += not accepted
        integrity = _integrity(scratch.target)
    finally:
        scratch.target.close()
    return {
        "cases": cases,
        "seed": seed,
        "seconds": round(time.perf_counter() - started, 1),
        "families": {family: tally.__dict__ for family, tally in tallies.items()},
        "tracebacks": sum(tally.tracebacks for tally in tallies.values()),
        "executed": scratch.marker.exists(),
        **integrity,
    }


def _integrity(league: League) -> dict[str, Any]:
    from league.sync.outgoing import unsent_batches

    check = league.query_one("PRAGMA integrity_check")
    damaged = [line for batch in unsent_batches(league, "nowhere") for line in batch.damaged]
    quarantined = league.query("SELECT reason, excerpt, location FROM sync_quarantine")
    unprintable = sum(
        1 for row in quarantined for text in row if not all(char.isprintable() for char in text)
    )
    return {
        "integrity_check": str(check[0]) if check else "missing",
        "rows_not_matching_their_hash": len(damaged),
        "quarantined": len(quarantined),
        "quarantine_texts_with_control_characters": unprintable,
        "accepted_rows": len(league.query("SELECT 1 FROM sync_seals")),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.league.fuzz", description=__doc__)
    parser.add_argument("--cases", type=int, default=10_000, help="inputs to try (all families)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="racer-tui-fuzz-") as tmp:
        root = Path(tmp)
        with home_at(root / "home"):
            report = run(args.cases, args.seed, root)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"{report['cases']} fuzzed inputs in {report['seconds']} s (seed {report['seed']})")
    print(f"{'family':<8} {'cases':>6} {'refused':>8} {'accepted':>9} {'tracebacks':>11}")
    for family, tally in report["families"].items():
        print(
            f"{family:<8} {tally['cases']:>6} {tally['refused']:>8} {tally['accepted']:>9} "
            f"{tally['tracebacks']:>11}"
        )
    print(
        f"executed: {'YES' if report['executed'] else 'nothing'}; league integrity "
        f"{report['integrity_check']}, {report['rows_not_matching_their_hash']} rows not "
        f"matching their hash; {report['quarantined']} quarantined, "
        f"{report['quarantine_texts_with_control_characters']} with control characters"
    )
    for family, tally in report["families"].items():
        for example in tally["examples"]:
            print(f"--- {family} traceback ---\n{example}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
