"""Racers' reward functions: load a DeepRacer `reward_function(params)` file and call it safely.

A reward function is ordinary Python written by the racer, so everything that can go wrong
with it (a syntax error, a failing import, an exception on some step, a reward that is not a
number) becomes a `RewardFunctionError`: one sentence naming the file and, where there is one,
the line in *their* file to look at. Training calls the function ~30,000 times a second, so the
happy path of `RewardFunction.__call__` is one dict copy, one call and one type check.

The reward templates (racer-tui's own code, paying what the DeepRacer console's templates
of the same names pay) ship as plain files in `sim/reward/templates/` and load through the
same path as a racer's file.
"""

from __future__ import annotations

import ast
import inspect
import linecache
import math
import numbers
import os
import sys
import time
import types
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from sim.reward import guard as reward_guard
from sim.reward import limit as reward_limit
from sim.reward import sandbox as reward_sandbox
from sim.reward.errors import FIX_ADVICE, RewardFunctionError
from sim.reward.guard import ForbiddenInReward
from sim.reward.limit import RewardTimeout

if TYPE_CHECKING:  # gymnasium's import is not needed to load a reward function
    pass

# DeepRacer rejects rewards outside this range (and NaN or inf).
MAX_ABS_REWARD = 1e5

RETURN_ADVICE = "make it return a number, for example `return float(reward)`"
DEFINE_HINT = "`def reward_function(params):`"

# The racer's module gets its own name so `if __name__ == "__main__":` test code in their file
# does not run, and it is never put in sys.modules so two loaded files cannot see each other.
_MODULE_NAME = "deepracer_reward_function"
# Exception messages are quoted inside one sentence; a numpy array repr can be pages long.
_MAX_DETAIL = 200

RewardParams = Mapping[str, object]


class RewardFunction:
    """A loaded reward function. Call it with DeepRacer params; it returns a checked float."""

    __slots__ = ("_filename", "_function", "name", "path", "source")

    def __init__(
        self,
        function: Callable[[dict[str, object]], object],
        *,
        source: str,
        name: str,
        filename: str,
    ) -> None:
        self._function = function
        # The file name the code was compiled with: traceback frames carrying it are the racer's.
        self._filename = filename
        self.source = source
        self.name = name
        self.path = Path(name)

    def __call__(self, params: RewardParams) -> float:
        limit = reward_limit._ACTIVE  # a process running racer code times every call
        if limit is not None:
            value = self._timed_call(limit, params)
        else:
            try:
                # A shallow copy: the racer's function may add, change or delete keys.
                value = self._function(dict(params))
            except BaseException as error:  # the racer's code may raise anything at all
                raise self._raised_error(error) from error
        # NaN and inf fail this comparison too, so only unusual values take the slow path.
        if type(value) is float and -MAX_ABS_REWARD <= value <= MAX_ABS_REWARD:
            return value
        return self._checked(value, params)

    def _timed_call(self, limit: reward_limit.CallLimit, params: RewardParams) -> object:
        started = limit.started = time.monotonic()
        try:
            try:
                value = self._function(dict(params))
                limit.started = 0.0  # from here no interruption can land
            except RewardTimeout as error:
                limit.started = 0.0
                raise self._timed_out(error) from None
            except BaseException as error:  # the racer's code may raise anything at all
                limit.started = 0.0
                raise self._raised_error(error) from error
        except RewardTimeout as late:  # landed in a handler above before it cleared the timer
            limit.started = 0.0
            raise self._timed_out(late) from None
        if limit.fired == started:  # it swallowed the interruption and returned later
            refused = reward_guard.take_refusal(started)
            if refused is not None:
                raise self._raised_error(refused)
            raise self._timed_out(RewardTimeout(limit.seconds))
        return value

    def __repr__(self) -> str:
        return f"RewardFunction({self.name!r})"

    def raw(self) -> tuple[Callable[[dict[str, object]], object], str]:
        """The racer's own function, uncalled and unchecked, and the file name its code was
        compiled with: for a check that judges what it returns as another validator does
        (`sim.reward.droa_rules`), in the contained child only."""
        return self._function, self._filename

    def first_line(self) -> int | None:
        """The line of `def reward_function` in the racer's file, when it is there."""
        code = _own_code(self._function, self._filename)
        return None if code is None else code.co_firstlineno

    def fresh(self) -> RewardFunction:
        """The same file loaded again into a module of its own.

        In DeepRacer a simulation worker drives one car and imports the reward module once,
        so module-level state (the previous step, a `Reward` object created at import)
        belongs to that car for the whole training (simapp `bundle/markov/rollout_worker.py`
        loads it once per worker). Training here drives many cars in one process: each car
        gets its own fresh module, or the cars would share that state.
        """
        return _load(self.source, self.name, self._filename)

    def __reduce__(self) -> tuple[Any, ...]:
        # Vector envs may pickle the env into worker processes; the function travels as source.
        return (_rebuild, (self.source, self.name, self._filename))

    # --- error paths (never on the hot path) -------------------------------------------
    def _timed_out(self, error: RewardTimeout) -> RewardFunctionError:
        line = _user_line(error, self._filename)
        where = " (stopped here)" if line is not None else ""
        return RewardFunctionError(
            self.name,
            f"reward_function did not return within {error.seconds:g} s{where}",
            line,
            advice="make it return faster (no loops that wait or never end)",
        )

    def _raised_error(self, error: BaseException) -> RewardFunctionError:
        return _failure(error, self.name, self._filename, "reward_function")

    def _checked(self, value: object, params: RewardParams) -> float:
        reward = _as_reward(value)
        if isinstance(reward, float):
            return reward
        line = self._return_line(params)
        raise RewardFunctionError(self.name, reward.problem, line, reward.advice)

    def _return_line(self, params: RewardParams) -> int | None:
        """The line of the `return` that produced a bad reward, else the `def` line.

        Python does not record where a value was returned, so this runs the function once more
        under a profiler that notes the line its frame returns from. That costs nothing on the
        hot path, and the run is about to stop on this error anyway. If the second run does not
        reproduce the problem (random numbers, state kept between calls) the `def` line is the
        honest answer.
        """
        code = _own_code(self._function, self._filename)
        if code is None:
            return None
        returned_from: list[int] = []

        def profiler(frame: types.FrameType, event: str, arg: object) -> None:
            if event == "return" and frame.f_code is code and frame.f_lineno is not None:
                returned_from.append(frame.f_lineno)

        previous = sys.getprofile()
        sys.setprofile(profiler)
        limit = reward_limit._ACTIVE
        if limit is not None:
            limit.begin()
        try:
            value = self._function(dict(params))
        except (Exception, SystemExit, RewardTimeout, ForbiddenInReward):
            return code.co_firstlineno
        finally:
            if limit is not None:
                limit.end()
            sys.setprofile(previous)
        if isinstance(_as_reward(value), float) or not returned_from:
            return code.co_firstlineno
        # The outermost call returns last; earlier entries are recursive calls.
        return returned_from[-1]


def load_reward_function(path: Path | str) -> RewardFunction:
    """Load a racer's reward function file (this runs its code: only where the racer
    trains or checks it, under `sim.reward.limit`).

    Raises `RewardFunctionError` when the file is missing, unreadable, not UTF-8, not valid
    Python, fails while importing, or does not define `reward_function(params)`.
    """
    # Absolute, so the traceback frames still match after a change of working directory.
    return _load(read_reward_file(path), str(path), os.path.abspath(path))


def read_reward_file(path: Path | str) -> str:
    """A reward function file's text, without running it; `RewardFunctionError` when it is
    missing, unreadable or not UTF-8."""
    display = str(path)
    file_path = Path(path)
    try:
        data = file_path.read_bytes()
    except FileNotFoundError:
        raise RewardFunctionError(
            display, "no such file", advice="check the path and try again"
        ) from None
    except IsADirectoryError:
        raise RewardFunctionError(
            display,
            "is a folder, not a Python file",
            advice="give the path of the reward function file",
        ) from None
    except OSError as error:
        raise RewardFunctionError(
            display,
            f"cannot be read ({error.strerror or error})",
            advice="check that the file exists and that you may read it",
        ) from None
    try:
        # utf-8-sig: editors on Windows often save a byte-order mark in front.
        source = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        raise RewardFunctionError(
            display,
            f"is not UTF-8 text (byte 0x{data[error.start]:02x})",
            line,
            advice="save it as UTF-8 and try again",
        ) from None
    return source


def check_reward_code(source: str, name: str) -> None:
    """Check reward function code without running a line of it: it must be Python and
    define `reward_function(params)` at the top level. Importing a model, saving one in
    the editor and creating one from a file check this much; the code itself runs only
    when the racer trains or checks it."""
    tree = _compiled_tree(source, name)
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.name == (
            "reward_function"
        ):
            if isinstance(node, ast.AsyncFunctionDef) or not _binds_one_argument(node.args):
                raise RewardFunctionError(
                    name,
                    "reward_function must take exactly one argument, params",
                    node.lineno,
                    advice=f"define it as {DEFINE_HINT} and try again",
                )
            return
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        if any(isinstance(t, ast.Name) and t.id == "reward_function" for t in targets):
            return  # made at load time (a factory, a lambda): the first check will tell
    raise RewardFunctionError(
        name, "no reward_function found", advice=f"the file must define {DEFINE_HINT}"
    )


def _compiled_tree(source: str, display: str) -> ast.Module:
    try:
        return ast.parse(source, display)
    except (SyntaxError, ValueError) as error:
        raise _not_python(error, display) from None


def _not_python(error: SyntaxError | ValueError, display: str) -> RewardFunctionError:
    if isinstance(error, SyntaxError):
        detail = error.msg or "invalid syntax"
        kind = type(error).__name__
        problem = "syntax error" if kind == "SyntaxError" else kind
        return RewardFunctionError(display, f"{problem}: {detail}", error.lineno)
    # Older Pythons report NUL bytes in source as ValueError rather than SyntaxError.
    return RewardFunctionError(
        display, f"is not valid Python source ({error})", advice="save it as plain text"
    )


def _binds_one_argument(arguments: ast.arguments) -> bool:
    """Whether `f(params)` binds: one positional parameter without a default (or *args),
    every other parameter optional."""
    positional = [*arguments.posonlyargs, *arguments.args]
    required = len(positional) - len(arguments.defaults)
    keyword_required = sum(default is None for default in arguments.kw_defaults)
    if keyword_required:
        return False
    return required == 1 or (required == 0 and (bool(positional) or arguments.vararg is not None))


def load_reward_source(source: str, name: str) -> RewardFunction:
    """Load reward function code held in memory; errors name it `name`."""
    return _load(source, name, name)


# --- loading -----------------------------------------------------------------------------


def _rebuild(source: str, name: str, filename: str) -> RewardFunction:
    return _load(source, name, filename)


def _load(source: str, display: str, filename: str) -> RewardFunction:
    try:
        code = compile(source, filename, "exec", dont_inherit=True)
    except (SyntaxError, ValueError) as error:
        raise _not_python(error, display) from None
    # Tracebacks then show the racer's lines as they were loaded, even from memory and even
    # if the file changes later; a None mtime keeps linecache.checkcache from dropping them.
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)

    module = types.ModuleType(_MODULE_NAME)
    module.__file__ = filename
    # The memory limit goes on before the timing begins: during the racer's code, changing
    # a limit is refused (sim.reward.sandbox), racer-tui's own change included.
    with reward_sandbox.loading_limit():
        _run_module(code, module, display, filename)

    function = module.__dict__.get("reward_function")
    if function is None:
        raise RewardFunctionError(
            display, "no reward_function found", advice=f"the file must define {DEFINE_HINT}"
        )
    if not callable(function):
        raise RewardFunctionError(
            display,
            f"reward_function is {_a(type(function).__name__)}, not a function",
            advice=f"the file must define {DEFINE_HINT}",
        )
    _check_takes_params(function, display, filename)
    return RewardFunction(function, source=source, name=display, filename=filename)


def _run_module(
    code: types.CodeType, module: types.ModuleType, display: str, filename: str
) -> None:
    """Run the racer's module-level code, timed; `RewardFunctionError` for what goes wrong."""
    limit = reward_limit._ACTIVE  # module-level code is the racer's too
    began = 0.0
    if limit is not None:
        limit.begin()
        began = limit.started
    try:
        exec(code, module.__dict__)
    except RewardTimeout as error:
        if limit is not None:
            limit.end()
        problem = f"loading the file did not finish within {error.seconds:g} s (stopped here)"
        line = _user_line(error, filename)
        raise RewardFunctionError(display, problem, line, "fix the file and try again") from None
    except BaseException as error:  # the racer's module-level code may raise anything
        if limit is not None:
            limit.end()
        raise _failure(error, display, filename, "loading the file") from error
    finally:
        if limit is not None:
            limit.end()
    refused = reward_guard.take_refusal(began) if limit is not None else None
    if refused is not None:  # it swallowed the refusal
        raise _failure(refused, display, filename, "loading the file")
    if limit is not None and limit.overran(began):  # it swallowed the interruption
        raise RewardFunctionError(
            display,
            f"loading the file did not finish within {limit.seconds:g} s",
            advice="fix the file and try again",
        )


def _check_takes_params(function: Callable[..., object], display: str, filename: str) -> None:
    """DeepRacer calls `reward_function(params)`: one positional argument must bind."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return  # Some callables have no introspectable signature; the first call will tell.
    try:
        signature.bind(None)
    except TypeError:
        code = _own_code(function, filename)
        line = None if code is None else code.co_firstlineno
        raise RewardFunctionError(
            display,
            f"reward_function{signature} must take exactly one argument, params",
            line,
            advice=f"define it as {DEFINE_HINT} and try again",
        ) from None


# --- checking results and describing failures --------------------------------------------
_TOO_LARGE = "reward_function returned a number too large to be a reward"


class _BadReward(NamedTuple):
    problem: str
    advice: str


def _as_reward(value: object) -> float | _BadReward:
    """The reward as a Python float, or what is wrong with it."""
    kind = type(value)
    # int and numpy float64 are common returns (`reward = 1`, `np.clip(...)`): test them by
    # exact type first, since the ABC checks below cost about a microsecond each call.
    if kind is int or kind is np.float64 or kind is float:
        try:
            reward = float(value)  # type: ignore[arg-type]
        except OverflowError:  # an int beyond any float, 10**400
            return _BadReward(_TOO_LARGE, "keep rewards within +-1e5")
    # bool is an int to Python, but a True/False reward is always a bug in the function.
    elif isinstance(value, bool | np.bool_):
        return _BadReward(
            f"reward_function returned {value!r} (a bool) instead of a number", RETURN_ADVICE
        )
    elif isinstance(value, numbers.Real) or _is_real_scalar_array(value):
        try:
            reward = float(value)  # type: ignore[arg-type]
        except OverflowError:
            return _BadReward(_TOO_LARGE, "keep rewards within +-1e5")
    elif value is None:
        return _BadReward("reward_function returned None instead of a number", RETURN_ADVICE)
    else:
        shown = _shorten(repr(value), 60)
        return _BadReward(
            f"reward_function returned {shown} ({_a(kind.__name__)}) instead of a number",
            RETURN_ADVICE,
        )
    if -MAX_ABS_REWARD <= reward <= MAX_ABS_REWARD:
        return reward
    if math.isnan(reward):
        return _BadReward("reward_function returned NaN (not a number)", FIX_ADVICE)
    if math.isinf(reward):
        return _BadReward(f"reward_function returned {reward}, an infinite reward", FIX_ADVICE)
    limit = int(MAX_ABS_REWARD)
    return _BadReward(
        f"reward_function returned {reward}, outside DeepRacer's allowed range -{limit}..{limit}",
        FIX_ADVICE,
    )


def _is_real_scalar_array(value: object) -> bool:
    # A 0-d array is what some numpy code hands back; DeepRacer's float() accepts it.
    return isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"


def _own_code(function: Callable[..., object], filename: str) -> types.CodeType | None:
    """The function's code object when it was written in the racer's file.

    A decorator from elsewhere puts its own code on the name; its line numbers belong to
    another file and must not be reported as lines of this one.
    """
    code = getattr(function, "__code__", None)
    if isinstance(code, types.CodeType) and code.co_filename == filename:
        return code
    return None


def _user_line(error: BaseException, filename: str) -> int | None:
    """The line of the deepest traceback frame that runs code from the racer's file."""
    line: int | None = None
    traceback = error.__traceback__
    while traceback is not None:
        if traceback.tb_frame.f_code.co_filename == filename:
            line = traceback.tb_lineno
        traceback = traceback.tb_next
    return line


def _failure(error: BaseException, display: str, filename: str, who: str) -> RewardFunctionError:
    """What `who` ("reward_function", "loading the file") raising `error` means, in one
    sentence: a thing a reward may not do, memory, an exit, or the exception itself."""
    line = _user_line(error, filename)
    advice = FIX_ADVICE if who == "reward_function" else "fix the file and try again"
    if isinstance(error, ForbiddenInReward):
        problem = f"{who} {error.action}, which a reward function may not do"
        return RewardFunctionError(display, problem, error.line_in(filename) or line, "remove it")
    megabytes = reward_sandbox.memory_limit_mb()
    if isinstance(error, MemoryError) and megabytes is not None:
        problem = reward_sandbox.memory_problem(megabytes, who)
        return RewardFunctionError(
            display, problem, line, "keep less in memory (smaller lists and arrays)"
        )
    if isinstance(error, SystemExit):
        problem = f"{who} calls sys.exit(), which would end its process"
        return RewardFunctionError(display, problem, line, "remove the exit() call")
    problem = f"{who} raised {_describe_exception(error)}"
    if isinstance(error, PermissionError) and reward_sandbox.files_guarded():
        advice = (
            "a reward function may read only Python's files and its own folder, and write nowhere"
        )
    return RewardFunctionError(display, problem, line, advice)


def _describe_exception(error: BaseException) -> str:
    name = type(error).__name__
    try:
        detail = _shorten(str(error), _MAX_DETAIL)
    except Exception:  # The racer's own exception class may have a broken __str__.
        detail = ""
    return f"{name}: {detail}" if detail else name


def _a(noun: str) -> str:
    return f"an {noun}" if noun[:1].lower() in "aeiou" else f"a {noun}"


def _shorten(text: str, limit: int) -> str:
    # The message must stay one line and one sentence inside our own.
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[: limit - 3] + "..."
