"""Would DeepRacer on AWS accept this reward function? Its validator's rules, applied here.

DeepRacer on AWS (DRoA) validates a reward function before a model is created or imported
(`source/libs/reward-function-validation/` in aws-solutions/deepracer-on-aws, Python 3.12);
a function racer-tui accepts may still be refused there. Its rules, in the order it
applies them, stopping at the first suite that fails and saying only the first problem:

1. at most 140,000 characters (its API's limit);
2. flake8 (7.3) with `--select=E,F --ignore=E5,E226,E261` and no configuration: the
   ignore list replaces flake8's default one, so E121, E123, E126, E24x and E704 count;
3. imports: every `import X` and `from X import ...`, anywhere in the file, of `math`,
   `random`, `numpy`, `scipy` or `shapely` only;
4. no call of the bare names `open`, `exec`, `eval`, `compile`, `input`; its walk over the
   calls and attributes also fails (with Python's "can only join an iterable") on a call
   or attribute whose chain does not start at a name (`"{}".format(x)`,
   `params["waypoints"][0].index`);
5. none of the substrings `__import__`, `load`, `fromfile`, `genfromtxt`, `loadtxt`,
   `tofile`, `savez`, `save`, `savetxt`, `memmap` anywhere in the text, comments and names
   included ("download" and "payload" hold "load");
6. called once with `__import__` made to fail: an import inside the function, or any
   other exception there, is refused;
7. exactly one parameter; then called on five synthetic states of the model's track, 5 s
   each: it must return a `float` (an `int` fails) within [-1e5, 1e5]. Those states lack
   `projection_distance` and `objects_distance_from_center`, and their `waypoints` are a
   numpy array of the track's inner border, not a list of tuples.

Steps 1-5 read the text (flake8 runs as its own program: nothing of the racer's code is
executed); steps 6-7 run the code, and only in the reward check's contained child process
(`sim.reward.probe`), with DRoA's 5 s per call. The messages are DRoA's own, so a racer
reads here what DRoA would say. racer-tui runs on Python 3.11: syntax only 3.12 knows is a
syntax error here and not there.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import json
import math
import subprocess
import sys
import tempfile
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sim.reward.errors import RewardFunctionError
from sim.tracks.catalog import find_track_info, resolve_track

MAX_CHARACTERS = 140_000
ALLOWED_IMPORTS = ("math", "random", "numpy", "scipy", "shapely")
FORBIDDEN_CALLS = ("open", "exec", "eval", "compile", "input")
FORBIDDEN_STRINGS = (
    "__import__",
    "load",
    "fromfile",
    "genfromtxt",
    "loadtxt",
    "tofile",
    "savez",
    "save",
    "savetxt",
    "memmap",
)
FLAKE8_OPTIONS = ("--select=E,F", "--ignore=E5,E226,E261")
CALL_SECONDS = 5.0  # DRoA's TIMEOUT_SEC for each runtime test
MAX_REWARD = 1e5
FLAKE8_SECONDS = 60.0

# DRoA's error types: flake8's codes besides these.
TEST_FAILURE = "TEST_FAILURE"
IMPORT_ERROR = "IMPORT_ERROR"
SYNTAX_ERROR = "SYNTAX_ERROR"
SIZE = "SIZE"  # refused by DRoA's API before the validator runs


@dataclass(frozen=True)
class DroaReason:
    """One thing DRoA refuses, as its validator says it."""

    kind: str  # DRoA's error type (TEST_FAILURE, IMPORT_ERROR, ...) or flake8's code
    message: str
    line: int | None = None

    def to_json(self) -> dict[str, Any]:
        return {"type": self.kind, "message": self.message, "line": self.line}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> DroaReason:
        line = data.get("line")
        return cls(
            str(data.get("type", "")),
            str(data.get("message", "")),
            line if isinstance(line, int) else None,
        )


# --- the text: size, flake8, imports, calls, strings --------------------------------------


def static_reasons(source: str) -> list[DroaReason]:
    """Everything DRoA refuses by reading the text, in its order (it says only the first)."""
    if len(source) > MAX_CHARACTERS:
        return [
            DroaReason(
                SIZE,
                f"The reward function has {len(source):,} characters; DeepRacer on AWS takes "
                f"at most {MAX_CHARACTERS:,}.",
            )
        ]
    reasons = run_flake8(source)
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError):
        return reasons  # flake8 has said it (E999)
    reasons += _import_reasons(tree)
    reasons += _call_reasons(tree)
    reasons += _string_reasons(source)
    return reasons


def run_flake8(source: str) -> list[DroaReason]:
    """flake8 as DRoA runs it, on the text written to a file of its own: every problem."""
    with tempfile.TemporaryDirectory(prefix="racer-droa-") as scratch:
        path = Path(scratch) / "reward_function.py"
        path.write_text(source, encoding="utf-8")
        try:
            done = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "flake8",
                    "--isolated",  # no configuration of the racer's own: DRoA has none
                    "--format=%(code)s:%(row)d:%(text)s",
                    *FLAKE8_OPTIONS,
                    str(path),
                ],
                capture_output=True,
                text=True,
                timeout=FLAKE8_SECONDS,
                cwd=scratch,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return [DroaReason(TEST_FAILURE, f"flake8 did not finish within {FLAKE8_SECONDS:g} s.")]
    if done.returncode not in (0, 1) or "No module named flake8" in done.stderr:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1][:200]
        raise RewardFunctionError(
            "DeepRacer on AWS's check",
            f"flake8, which it runs, could not run here ({last})",
            advice="reinstall racer-tui (its dependencies include flake8 7.3.0)",
        )
    return [_flake8_reason(line) for line in done.stdout.splitlines() if line.strip()]


def _flake8_reason(line: str) -> DroaReason:
    code, _, rest = line.partition(":")
    row, _, text = rest.partition(":")
    number = int(row) if row.isdigit() else None
    if code == "E999":
        # DRoA splits the line on ':' and takes the exception's name as the type.
        kind, _, message = text.partition(":")
        return DroaReason(kind.strip() or code, message.strip(), number)
    return DroaReason(code, text, number)


def _import_reasons(tree: ast.Module) -> list[DroaReason]:
    refused: dict[str, int] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.module is None:  # `from . import x`: DRoA's check fails on it
                return [
                    DroaReason(
                        TEST_FAILURE, "'NoneType' object has no attribute 'split'", node.lineno
                    )
                ]
            names = [node.module]
        else:
            continue
        for name in names:
            top = name.split(".")[0]
            if top not in ALLOWED_IMPORTS:
                refused.setdefault(top, node.lineno)
    if not refused:
        return []
    return [
        DroaReason(
            TEST_FAILURE,
            f"The reward function contains illegal import(s): {sorted(refused)}",
            min(refused.values()),
        )
    ]


class _ChainError(Exception):
    def __init__(self, line: int) -> None:
        self.line = line


def _call_reasons(tree: ast.Module) -> list[DroaReason]:
    names: list[tuple[str, int]] = []
    try:
        _collect_calls(tree, names)
    except _ChainError as error:
        return [DroaReason(TEST_FAILURE, "can only join an iterable", error.line)]
    forbidden = [(name, line) for name, line in names if name in FORBIDDEN_CALLS]
    if not forbidden:
        return []
    return [
        DroaReason(
            TEST_FAILURE,
            f"The reward function contains forbidden builtins: {[n for n, _ in forbidden]}",
            forbidden[0][1],
        )
    ]


def _collect_calls(node: ast.AST, names: list[tuple[str, int]]) -> None:
    """DRoA's walk: every call or attribute is named by its dotted chain (a call's
    positional arguments are walked too, nothing else inside it); other nodes are walked
    field by field. A chain that does not start at a plain name cannot be named."""
    if isinstance(node, ast.Call | ast.Attribute):
        names.append((".".join(_chain(node, names)), node.lineno))
        return
    for child in ast.iter_child_nodes(node):
        _collect_calls(child, names)


def _chain(node: ast.expr, names: list[tuple[str, int]]) -> list[str]:
    parts: list[str] = []
    while True:
        if isinstance(node, ast.Name):
            return [node.id, *parts]
        if isinstance(node, ast.Call):
            for argument in node.args:
                _collect_calls(argument, names)
            node = node.func
        elif isinstance(node, ast.Attribute):
            parts.insert(0, node.attr)
            node = node.value
        else:
            raise _ChainError(getattr(node, "lineno", 1))


def _string_reasons(source: str) -> list[DroaReason]:
    for text in FORBIDDEN_STRINGS:
        if text in source:
            line = source[: source.index(text)].count("\n") + 1
            return [
                DroaReason(
                    TEST_FAILURE,
                    f'Your code snippet contains a restricted string "{text}" that is not '
                    "allowed. Please remove or replace the string and try again.",
                    line,
                )
            ]
    return []


# --- the code run: in the check's contained child only ----------------------------------


def route_of(track: str) -> np.ndarray[Any, Any]:
    """The (N, 6) route DRoA's validator loads for `track`: the track's own `.npy` as
    DeepRacer ships it (a racer-tui track built here: its points)."""
    info = find_track_info(track)
    try:
        raw = np.load(info.path, allow_pickle=False)
    except (OSError, ValueError):
        raw = None
    if isinstance(raw, np.ndarray) and raw.ndim == 2 and raw.shape[1] == 6 and len(raw) >= 3:
        return raw.astype(np.float64)
    return resolve_track(track).points


def synthetic_states(route: np.ndarray[Any, Any]) -> list[dict[str, Any]]:
    """DRoA's five states for a track's (N, 6) route: a valid start between the centre and
    the inner border, the start line, halfway, off track, the finish. Their values follow
    DRoA's test (the speeds 0.1-5.0, `is_reversed` true, six objects on every track)."""
    inner = route[:, 2:4]
    count = route.shape[0]
    width = math.hypot(route[0, 4] - route[0, 2], route[0, 5] - route[0, 3])
    length = sum(
        math.hypot(inner[i, 0] - inner[i - 1, 0], inner[i, 1] - inner[i - 1, 1])
        for i in range(1, count)
    )
    reach = math.hypot(route[0, 4] - route[0, 0], route[0, 5] - route[0, 1])
    off_x = route[0, 0] + (route[0, 4] - route[0, 0]) / reach * width
    off_y = route[0, 1] + (route[0, 5] - route[0, 1]) / reach * width
    middle = math.floor(count / 2)

    def state(**values: Any) -> dict[str, Any]:
        return {
            "all_wheels_on_track": True,
            "distance_from_center": 0,
            "heading": 359.9,
            "track_width": width,
            "waypoints": inner,
            "is_left_of_center": True,
            "is_reversed": True,
            "track_length": length,
            "closest_objects": [0, 1],
            "objects_location": [list(xy) for xy in _OBJECT_LOCATIONS],
            "objects_left_of_center": [True, True, False, True, False, True],
            "object_in_camera": True,
            "objects_speed": [0.2] * 6,
            "objects_heading": list(_OBJECT_HEADINGS),
            "objects_distance": list(_OBJECT_DISTANCES),
            "is_crashed": False,
            "is_offtrack": False,
            **values,
        }

    start = {"progress": 0, "steps": 1, "closest_waypoints": [0, 1]}
    return [
        state(
            x=(route[0, 2] + route[0, 0]) / 2,
            y=(route[0, 3] + route[0, 1]) / 2,
            heading=0,
            speed=0.5,
            steering_angle=6,
            **start,
        ),
        state(x=route[0, 2], y=route[0, 3], heading=0, speed=0.1, steering_angle=0.2, **start),
        state(
            x=route[middle, 2],
            y=route[middle, 3],
            progress=50,
            steps=100,
            speed=1.0,
            steering_angle=6,
            closest_waypoints=[3, 4],
        ),
        state(
            all_wheels_on_track=False,
            x=off_x,
            y=off_y,
            distance_from_center=width,
            speed=1,
            steering_angle=15,
            is_offtrack=True,
            **start,
        ),
        state(
            x=route[count - 1, 2],
            y=route[count - 1, 3],
            progress=100,
            steps=10000,
            speed=5.0,
            steering_angle=0,
            closest_waypoints=[count - 2, count - 1],
        ),
    ]


_OBJECT_LOCATIONS = (
    (4.511289152034186, 1.3292364463761641),
    (6.537302737755836, 1.4140104486149618),
    (4.752976532490525, 3.1350845729056838),
    (3.103370840828792, 4.133062703357412),
    (0.7094212601659824, 4.217507179944688),
    (1.5996645329306798, 1.7124666440529925),
)
_OBJECT_HEADINGS = (
    2.717322296283114,
    2.368920328229894,
    -1.9305073380382327,
    -1.3586571052564007,
    0.00025041038280975884,
    0.5573269195381345,
)
_OBJECT_DISTANCES = (
    1.9501724549506574,
    4.139700164331426,
    7.997164727523002,
    10.024219705986598,
    12.56561517097048,
    15.090712948383509,
)
# DRoA's runtime tests on the five states, in its order: the state, and its message.
_STATE_TESTS = (
    (1, "Vehicle failed at start position. Reward: {}"),
    (2, "Vehicle failed to make progress. Reward: {}"),
    (3, "Off-track vehicle failed to make progress. Reward: {}"),
    (4, "Vehicle failed to make it to end of track. Reward: {}"),
)


class Outcome:
    """What one call gave: a value, or the exception it raised, or nothing in time."""

    def __init__(
        self, value: object = None, error: BaseException | None = None, timed_out: bool = False
    ) -> None:
        self.value = value
        self.error = error
        self.timed_out = timed_out


def runtime_reasons(
    function: Callable[..., object],
    states: list[dict[str, Any]],
    call: Callable[[Callable[[], object]], Outcome],
    filename: str,
) -> list[DroaReason]:
    """DRoA's run of the code (steps 6-7), with `call` running each call under its time
    limit. Stops where DRoA stops: after the import check fails, and at the first state
    that fails (the later ones fail the same way or say nothing new)."""

    def refuse_import(name: str, *_args: object, **_kwargs: object) -> object:
        message = "Import should be put at the top of file, module: " + name
        raise _DroaImportError(json.dumps({"message": message, "type": IMPORT_ERROR}))

    real_import = builtins.__import__
    # DRoA swaps the interpreter's import hook itself; its signature is looser here.
    builtins.__import__ = refuse_import  # type: ignore[assignment]
    try:
        first = call(lambda: function(dict(states[0])))
    finally:
        builtins.__import__ = real_import
    if first.timed_out:
        return [DroaReason(TEST_FAILURE, "Timed Out")]
    if first.error is not None:
        return [
            DroaReason(
                TEST_FAILURE,
                f'Unsafe builtin function detected: "{first.error}".',
                _own_line(first.error, filename),
            )
        ]
    try:
        parameters = len(_signature_parameters(function))
    except (TypeError, ValueError):
        parameters = -1
    if parameters != 1:
        return [
            DroaReason(
                TEST_FAILURE,
                "Invalid reward function signature. Should be def reward_function(params)",
            )
        ]
    valid = call(lambda: function(dict(states[0])))
    problem = _outcome_problem(valid, filename)
    if problem is not None:
        return [problem]
    if not isinstance(valid.value, float):
        return [DroaReason(TEST_FAILURE, f"Method returned non-floating type value: {valid.value}")]
    if not _in_range(valid.value):
        return [
            DroaReason(
                TEST_FAILURE,
                f"Reward score out of range. Reward: {valid.value}, range: [-1e5, 1e5]",
            )
        ]
    for index, message in _STATE_TESTS:
        outcome = call(lambda index=index: function(dict(states[index])))  # type: ignore[misc]
        problem = _outcome_problem(outcome, filename)
        if problem is not None:
            return [problem]
        if not _in_range(outcome.value):
            return [DroaReason(TEST_FAILURE, message.format(outcome.value))]
    return []


class _DroaImportError(Exception):
    """What DRoA's import hook raises: its text is DRoA's JSON."""


def _signature_parameters(function: Callable[..., object]) -> Mapping[str, object]:
    return inspect.signature(function).parameters


def _in_range(value: object) -> bool:
    return isinstance(value, float) and -MAX_REWARD <= value <= MAX_REWARD


def _outcome_problem(outcome: Outcome, filename: str) -> DroaReason | None:
    if outcome.timed_out:
        return DroaReason(TEST_FAILURE, "Timed Out")
    if outcome.error is None:
        return None
    # DRoA's wrap: the text after the first ':' of the exception's last line.
    last = traceback.format_exception_only(outcome.error)[-1].strip()
    message = last.split(":", 1)[1].strip() if ":" in last else ""
    kind = IMPORT_ERROR if isinstance(outcome.error, ImportError) else TEST_FAILURE
    return DroaReason(kind, message, _own_line(outcome.error, filename))


def _own_line(error: BaseException, filename: str) -> int | None:
    line = None
    for frame in traceback.extract_tb(error.__traceback__):
        if frame.filename == filename:
            line = frame.lineno
    return line
