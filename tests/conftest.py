"""Shared fixtures. Every test runs with RACER_TUI_HOME in a temp dir: no real data is touched."""

from __future__ import annotations

import contextlib
import gc
import itertools
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests import textual_css, textual_idle

REPO_ROOT = Path(__file__).resolve().parent.parent
SHARED_DEEPRACER = REPO_ROOT.parent / "shared" / "deepracer"


textual_idle.install()
textual_css.install()

# A test process holds what every test before it imported and kept (torch, Textual, the
# app's modules and caches): a million objects, which every full collection walked again.
# That was about a tenth of the suite's time. What has lived through a collection is frozen
# out of collection (`gc.freeze`) after collecting and then every few tests: garbage made
# since is collected as usual, and the frozen stays, as it would have in any case: it was
# alive. (An object frozen while alive and left in a cycle later is never freed: a little
# memory for the rest of the process, against minutes of the suite.)
FREEZE_EVERY_TESTS = 10
_tests_run = itertools.count(1)


def _collect_and_freeze() -> None:
    gc.collect()
    gc.freeze()


def pytest_collection_finish(session: pytest.Session) -> None:
    _collect_and_freeze()


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> None:
    if next(_tests_run) % FREEZE_EVERY_TESTS == 0:
        _collect_and_freeze()


@pytest.fixture(autouse=True)
def racer_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    home = tmp_path / "racer-home"
    monkeypatch.setenv("RACER_TUI_HOME", str(home))
    # `racer-tui --db FILE` sets RACER_TUI_LEAGUE for the rest of its process; a test that
    # runs the CLI's main in-process must not leave it to the tests after it ("" is unset).
    monkeypatch.setenv("RACER_TUI_LEAGUE", "")
    yield home


@pytest.fixture
def deepracer_dir() -> Path:
    """The real AWS DeepRacer files in ../shared/deepracer (skips when absent)."""
    if not SHARED_DEEPRACER.is_dir():
        pytest.skip(
            "../shared/deepracer is not beside this checkout; real DeepRacer files unavailable"
        )
    return SHARED_DEEPRACER


@pytest.fixture
def no_leftover_processes() -> Iterator[None]:
    """After a test that makes reward code start processes: end any it left behind, so a
    test that fails (and cannot check for them) never leaves an endless loop eating a core
    for the rest of the run. Those are the tests' endless loops and sleeps reparented to
    init since the test began (another worker's processes are none of these)."""
    import time

    import psutil

    began = time.time() - 1.0
    yield
    for process in psutil.process_iter(["ppid", "create_time", "cmdline"]):
        command = " ".join(process.info["cmdline"] or [])
        left = "while True" in command or command.startswith("sleep ")
        if left and process.info["ppid"] == 1 and process.info["create_time"] >= began:
            with contextlib.suppress(psutil.Error):
                process.kill()
