"""Shared fixtures. Every test runs with RACER_TUI_HOME in a temp dir: no real data is touched."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests import textual_css, textual_idle

REPO_ROOT = Path(__file__).resolve().parent.parent
SHARED_DEEPRACER = REPO_ROOT.parent / "shared" / "deepracer"


textual_idle.install()
textual_css.install()


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
