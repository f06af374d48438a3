"""Run a racer's reward function away from the caller: in a child process of its own
session, with a time limit on every call, a deadline on the whole check, a memory limit,
no process left behind and (where Linux has Landlock) no file outside Python's and its own
folder to read and none to write (sim.reward.sandbox). It keeps the caller's process from
running, hanging on or crashing with the code.

`racer-tui reward check` and the model editor's Check ask `check_reward_source`: the
child (`python -m sim.reward.probe`) loads the code, calls it on DeepRacer-complete sample
params and, when a track is given, on every step of the reference driver's lap, and
answers with one JSON line. `map_reward_source` asks the child for a reward map instead
(`sim.reward.map`). Whatever the code does (loops forever, sleeps, prints, exits
its process, starts a process, allocates without bound, raises KeyboardInterrupt), the
caller gets a `ProbeReport` or a `RewardFunctionError` in one sentence, its own process
never ran a line of it, and no process of the check outlives it. What the function prints
goes to /dev/null, never to a pipe the caller waits on. (Code that means to can get past
the audit guard and write a false answer: the check is for the racer's own use.)
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.reference_driver import ReferenceDriver
from sim.physics.simulation import TrackSimulation
from sim.reward import droa_rules
from sim.reward import guard as reward_guard
from sim.reward import limit as reward_limit
from sim.reward import sandbox as reward_sandbox
from sim.reward.errors import RewardFunctionError
from sim.reward.function import RewardFunction, load_reward_source
from sim.reward.lap import CENTRE_LINE, LINES, LapPay, lap_rewards
from sim.reward.limit import DEFAULT_SECONDS, RewardTimeout
from sim.reward.map import MapOptions, RewardMap, compute_map
from sim.reward.sample_params import sample_params
from sim.reward.sandbox import DEFAULT_MEMORY_MB
from sim.tracks.catalog import resolve_track

# The whole check (interpreter start, imports, the reference lap) must end within this;
# a function slow enough to miss it would make training crawl anyway.
CHECK_DEADLINE_SECONDS = 60.0
MAX_LAP_STEPS = 15 * 120  # two minutes at DeepRacer's 15 steps a second


@dataclass(frozen=True)
class ProbeReport:
    sample_reward: float
    track: str | None  # the track the reference lap was scored on, if any
    lap_rewards: tuple[float, ...]
    # "applied" when Landlock closed off the files, else why not (sim.reward.sandbox)
    landlock: str = ""


def check_reward_source(
    source: str,
    name: str,
    *,
    track: str | None = None,
    seconds: float = DEFAULT_SECONDS,
    deadline: float = CHECK_DEADLINE_SECONDS,
    memory_mb: int = DEFAULT_MEMORY_MB,
) -> ProbeReport:
    """Run the code named `name` (a file path or a template's file name) in a child
    process; raise `RewardFunctionError` for anything wrong with it."""
    ok = _ask_child("check", source, name, seconds, deadline, track=track, memory_mb=memory_mb)
    return ProbeReport(
        float(ok["sample_reward"]),
        ok["track"],
        tuple(ok["lap_rewards"]),
        str(ok.get("landlock", "")),
    )


def droa_runtime_reasons(
    source: str, name: str, track: str, *, memory_mb: int = DEFAULT_MEMORY_MB
) -> list[droa_rules.DroaReason]:
    """DeepRacer on AWS's run of the code on `track`'s route, in a child process: what
    it refuses (`sim.reward.droa_rules`), empty when it would accept the run."""
    # Each of DRoA's up to six calls may take its 5 s; the deadline leaves the child room.
    deadline = CHECK_DEADLINE_SECONDS + 6 * droa_rules.CALL_SECONDS
    ok = _ask_child(
        "droa", source, name, droa_rules.CALL_SECONDS, deadline, track=track, memory_mb=memory_mb
    )
    return [droa_rules.DroaReason.from_json(reason) for reason in ok["reasons"]]


@dataclass(frozen=True)
class EditorCheck:
    """The editor's Check in one child process: the sample, the map, the laps."""

    sample_reward: float
    reward_map: RewardMap
    laps: tuple[LapPay, ...]


def editor_check(
    source: str,
    name: str,
    track: str,
    options: MapOptions,
    speeds: tuple[float, ...],
    *,
    seconds: float = DEFAULT_SECONDS,
    deadline: float = CHECK_DEADLINE_SECONDS,
) -> EditorCheck:
    extra = {**_map_request(track, options), "speeds": list(speeds)}
    ok = _ask_child("editor", source, name, seconds, deadline, **extra)
    return EditorCheck(
        float(ok["sample_reward"]), RewardMap.from_json(ok["map"]), _laps(ok["laps"])
    )


def _map_request(track: str, options: MapOptions) -> dict[str, Any]:
    return {
        "track": track,
        "spacing": options.spacing,
        "speed": options.speed,
        "heading": options.heading,
    }


def _laps(rows: list[dict[str, Any]]) -> tuple[LapPay, ...]:
    return tuple(LapPay.from_json(row) for row in rows)


def map_reward_source(
    source: str,
    name: str,
    track: str,
    options: MapOptions,
    *,
    seconds: float = DEFAULT_SECONDS,
    deadline: float = CHECK_DEADLINE_SECONDS,
) -> RewardMap:
    """What the code pays over `track` (see sim.reward.map), computed in a child process."""
    ok = _ask_child("map", source, name, seconds, deadline, **_map_request(track, options))
    return RewardMap.from_json(ok["map"])


def lap_pay_of_source(
    source: str,
    name: str,
    track: str,
    speeds: tuple[float, ...],
    lines: tuple[str, ...] = LINES,
    *,
    seconds: float = DEFAULT_SECONDS,
    deadline: float = CHECK_DEADLINE_SECONDS,
) -> list[LapPay]:
    """What the code pays for one lap of each line at each speed (sim.reward.lap),
    computed in a child process."""
    ok = _ask_child(
        "lap", source, name, seconds, deadline, track=track, speeds=list(speeds), lines=list(lines)
    )
    return list(_laps(ok["laps"]))


def _ask_child(
    mode: str, source: str, name: str, seconds: float, deadline: float, **extra: Any
) -> dict[str, Any]:
    """The child's answer to one request (its "ok" part), or RewardFunctionError."""
    request = {"mode": mode, "source": source, "name": name, "seconds": seconds, **extra}
    child = subprocess.Popen(
        # -P: a `sim` folder in the working directory must not stand in for ours.
        [sys.executable, "-P", "-m", "sim.reward.probe"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,  # the function's prints: unbounded, and not ours
        # Its own session: whatever the function starts is in its process group, killed
        # as a whole below however the check ends.
        start_new_session=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        stdout, _ = child.communicate(json.dumps(request).encode("utf-8"), timeout=deadline)
    except subprocess.TimeoutExpired:
        stdout = None
    finally:
        # The child kills its own descendants before it answers; this ends what is left of
        # its session (the group outlives its leader while any member lives, so its id
        # cannot have been given to another process).
        reward_sandbox.kill_session(child.pid)
        if child.stdout is not None:
            child.stdout.close()
        child.wait()
    if stdout is None:
        raise RewardFunctionError(
            name,
            f"the check did not finish within {deadline:g} s, so it was stopped",
            advice="make the function return faster (each call should take well under "
            f"{seconds:g} s)",
        ) from None
    answer = _answer(stdout)
    if answer is None:
        if child.returncode < 0:
            raise RewardFunctionError(
                name,
                f"the check's process was killed (signal {-child.returncode}) before it answered",
                advice="if it ran out of memory, make the function use less; then try again",
            )
        raise RewardFunctionError(
            name,
            f"the function ended its own process (exit code {child.returncode}) instead of "
            "returning a reward",
            advice="remove the exit() or os._exit() call",
        )
    try:
        if "error" in answer:
            error = answer["error"]
            failed = RewardFunctionError(
                str(error["display"]),
                str(error["problem"]),
                error["line"] if isinstance(error["line"], int) else None,
                str(error["advice"]),
            )
        else:
            return dict(answer["ok"])
    except (KeyError, TypeError, ValueError):
        raise RewardFunctionError(
            name,
            "the check's answer was not in the form racer-tui writes (did the function write "
            "to the process's outputs?)",
            advice="remove the code that writes there and try again",
        ) from None
    raise failed  # outside the try: it is a ValueError too


def _answer(stdout: bytes) -> dict[str, Any] | None:
    """The child's one JSON line, or None when it never wrote one."""
    for line in reversed(stdout.splitlines()):
        try:
            answer = json.loads(line)
        except ValueError:
            continue
        if isinstance(answer, dict) and ("ok" in answer or "error" in answer):
            return answer
    return None


# --- the child ---------------------------------------------------------------------------


class _Watched:
    """A reward function whose every call is followed by a look for a process it left:
    what the audit guard cannot see (a multiprocessing "spawn" start) is caught here."""

    def __init__(self, reward: RewardFunction) -> None:
        self.reward = reward
        self._left_one(loading=True)

    def __call__(self, params: Any) -> float:
        value = self.reward(params)
        self._left_one()
        return value

    def fresh(self) -> _Watched:
        return _Watched(self.reward.fresh())

    def _left_one(self, *, loading: bool = False) -> None:
        if reward_sandbox.has_child_process():
            reward_sandbox.end_descendants()
            who = "loading the file" if loading else "reward_function"
            raise RewardFunctionError(
                self.reward.name,
                f"{who} starts a process that outlives the call, which a reward function "
                "may not do",
                None if loading else self.reward.first_line(),
                "remove it",
            )


def _probe(request: dict[str, Any], track: Any) -> dict[str, Any]:

    name = str(request["name"])
    mode = request.get("mode")
    if mode == "droa":
        return {"ok": {"reasons": _droa_reasons(request, track)}}
    reward = _Watched(load_reward_source(str(request["source"]), name))
    if mode in ("lap", "map", "editor"):
        answer: dict[str, Any] = {}
        if mode == "editor":
            answer["sample_reward"] = reward(sample_params())
        if mode in ("lap", "editor"):
            answer["laps"] = _lap_answer(reward.fresh(), track, request)
        if mode in ("map", "editor"):
            answer["map"] = _map_answer(reward.fresh(), track, request)
        return {"ok": answer}
    sample = reward(sample_params())
    lap: Sequence[float] = ()
    shown_track = None
    if track is not None:
        shown_track = track.name
        # The lap runs on the file loaded afresh, as a DeepRacer worker starts with it:
        # state the sample call left in the module does not leak into the lap.
        lap = _reference_lap_rewards(reward.fresh(), track)
    answer = {"sample_reward": sample, "track": shown_track, "lap_rewards": list(lap)}
    return {"ok": {**answer, "landlock": reward_sandbox.landlock_status()}}


def _droa_reasons(request: dict[str, Any], route: Any) -> list[dict[str, Any]]:
    """DeepRacer on AWS's run of the code (`sim.reward.droa_rules`): loaded as a module,
    then called as its validator calls it, each call under DRoA's 5 s."""

    name = str(request["name"])
    try:
        loaded = load_reward_source(str(request["source"]), name)
    except RewardFunctionError as error:
        # DRoA's module import fails the same way; its words are Python's.
        return [droa_rules.DroaReason(droa_rules.TEST_FAILURE, error.reason, error.line).to_json()]
    function, filename = loaded.raw()
    limit = reward_limit.active()

    def call(run: Any) -> droa_rules.Outcome:
        assert limit is not None  # main() installs it before anything runs
        limit.begin()
        try:
            value = run()
        except RewardTimeout:
            return droa_rules.Outcome(timed_out=True)
        except BaseException as error:  # the racer's code may raise anything at all
            return droa_rules.Outcome(error=error)
        finally:
            limit.end()
        return droa_rules.Outcome(value)

    states = droa_rules.synthetic_states(route)
    return [r.to_json() for r in droa_rules.runtime_reasons(function, states, call, filename)]


def _lap_answer(reward: Any, track: Any, request: dict[str, Any]) -> list[dict[str, Any]]:

    speeds = tuple(float(speed) for speed in request["speeds"])
    lines = tuple(str(line) for line in request.get("lines", (CENTRE_LINE,)))
    pays = lap_rewards(reward, track, speeds, lines)
    return [pay.to_json() for pay in pays]


def _map_answer(reward: Any, track: Any, request: dict[str, Any]) -> dict[str, Any]:

    heading = request.get("heading")
    options = MapOptions(
        float(request["spacing"]),
        float(request["speed"]),
        None if heading is None else float(heading),
    )
    return compute_map(reward, track, options).to_json()


def _reference_lap_rewards(reward: Any, track: Any) -> list[float]:

    sim = TrackSimulation(track, 1)
    driver = ReferenceDriver(track)
    sim.reset_car(0, start_s=0.0)
    rewards: list[float] = []
    for _ in range(MAX_LAP_STEPS):
        sim.apply(*driver.act(sim))
        if sim.steps[0] > 1:  # step 1 is DeepRacer's prepare step: the function is not called
            rewards.append(float(reward(sim.all_params()[0])))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    return rewards


def _error_answer(
    display: str, problem: str, advice: str, line: int | None = None
) -> dict[str, Any]:
    return {"error": {"display": display, "problem": problem, "line": line, "advice": advice}}


def _prepare(request: dict[str, Any]) -> Any:
    """Everything the check reads, read before the files are closed off: its modules and
    the track (a .npy path may be anywhere)."""

    track_name = request.get("track")
    if request.get("mode") == "droa":
        return droa_rules.route_of(str(track_name))
    if not track_name:
        return None

    return resolve_track(str(track_name))


def main() -> int:
    # The answer goes to the real stdout; anything the racer's code prints goes to stderr
    # (/dev/null), so a print() in the function cannot be taken for the answer.
    answer_stream = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    request = json.loads(sys.stdin.buffer.read().decode("utf-8"))
    name = str(request.get("name"))

    def say(answer: dict[str, Any]) -> None:
        answer_stream.write(json.dumps(answer) + "\n")
        answer_stream.flush()

    def stuck(error: RewardFunctionError) -> None:
        say(_error_answer(error.display, error.reason, error.advice, error.line))

    reward_sandbox.become_subreaper()  # orphans of the function stay ours to end
    reward_sandbox.install_call_limit(float(request.get("seconds", DEFAULT_SECONDS)), name, stuck)
    reward_guard.guard_reward_calls()
    try:
        track = _prepare(request)
        reward_sandbox.preimport(str(request["source"]))
        reward_sandbox.close_off_files(name)
        reward_sandbox.limit_memory(int(request.get("memory_mb", DEFAULT_MEMORY_MB)))
        answer = _probe(request, track)
    except RewardFunctionError as error:
        answer = _error_answer(error.display, error.reason, error.advice, error.line)
    except MemoryError:  # the function's memory, filled where racer-tui's code ran next
        megabytes = reward_sandbox.memory_limit_mb() or DEFAULT_MEMORY_MB
        answer = _error_answer(
            name, reward_sandbox.memory_problem(megabytes), "keep less in memory"
        )
    except BaseException as error:  # the track, or an interrupt
        answer = _error_answer(
            name,
            f"the check could not run ({type(error).__name__}: {error})",
            "fix that and try again",
        )
    reward_sandbox.end_descendants()
    say(answer)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
