"""An automatic timer's lines, read from a pseudo-terminal (as a USB serial timer appears)
and from a named pipe."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from league.timekeeper.feed import FeedError, Trigger, check_timer_path, follow, parse_trigger


@contextmanager
def reading(path: str) -> Iterator[list[str]]:
    """The lines `follow` reads from `path`, in a thread, until the block ends."""
    got: list[str] = []
    stop = threading.Event()
    thread = threading.Thread(target=lambda: got.extend(line for _, line in follow(path, stop)))
    thread.start()
    try:
        yield got
    finally:
        stop.set()
        thread.join(timeout=5)
        assert not thread.is_alive()


def wait_until(condition: Callable[[], bool], seconds: float = 5.0) -> None:
    event = threading.Event()
    for _ in range(int(seconds / 0.02)):
        if condition():
            return
        event.wait(0.02)
    raise AssertionError("timed out")


def test_lines_from_a_serial_device_arrive_as_the_timer_sends_them() -> None:
    controller, device = os.openpty()
    try:
        with reading(os.ttyname(device)) as got:
            os.write(controller, b"lap\r\n")
            os.write(controller, b"res")  # a line arrives in pieces
            wait_until(lambda: got == ["lap"])
            os.write(controller, b"et\r\n# a comment\r\n")
            wait_until(lambda: len(got) == 3)
        assert [parse_trigger(line) for line in got] == [Trigger.LAP, Trigger.RESET, None]
    finally:
        os.close(controller)
        os.close(device)


def test_a_named_pipe_is_followed_across_writers(tmp_path: Path) -> None:
    pipe = tmp_path / "timer"
    os.mkfifo(pipe)
    with reading(str(pipe)) as got:
        for count, line in enumerate((b"lap\n", b"LAP\n"), start=1):  # two writers in turn
            with pipe.open("wb") as writer:
                writer.write(line)
            wait_until(lambda count=count: len(got) == count)
    assert [parse_trigger(line) for line in got] == [Trigger.LAP, Trigger.LAP]


def test_what_is_not_a_timer_is_said_in_one_sentence(tmp_path: Path) -> None:
    plain = tmp_path / "laps.txt"
    plain.write_text("lap\n")
    assert (
        check_timer_path(str(plain))
        == f"The timer {plain} is neither a serial device nor a named pipe."
    )
    assert "cannot be found" in str(check_timer_path(str(tmp_path / "missing")))
    with pytest.raises(FeedError, match="neither 'lap' nor 'reset'"):
        parse_trigger("go!")
    with pytest.raises(FeedError, match="cannot be found"):
        next(follow(str(tmp_path / "missing"), threading.Event()))
