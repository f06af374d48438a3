"""`racer-tui serve`: the league's leaderboard and a night as web pages and JSON, read-only
(`racer_tui.web`)."""

from __future__ import annotations

import argparse
import os
import signal
from pathlib import Path

from league.store import default_db_path
from sim.foundation.parent import die_with_parent
from sim.foundation.remedies import RemedyError

NAMES = ("serve",)
DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8080


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    serve = commands.add_parser(
        "serve",
        help="the leaderboard and a league night as web pages and JSON, read-only",
        description="Serve the league read-only on the web: the leaderboard at /, a night at "
        "/night, both as JSON under /api/. Only this machine can open it unless --host says "
        "otherwise.",
    )
    serve.add_argument(
        "--night", metavar="NIGHT", help="the night /night shows (default: the newest open night)"
    )
    serve.add_argument(
        "--host",
        default=DEFAULT_HOST,
        help=f"the address to listen on "
        f"(default {DEFAULT_HOST}: this machine only; 0.0.0.0 for the network)",
    )
    serve.add_argument(
        "--port",
        type=int,
        default=DEFAULT_PORT,
        help=f"the port (default {DEFAULT_PORT}; 0 picks a free one)",
    )
    serve.add_argument("--db", type=Path, help="the league database (default: the app's)")
    # The app's own server: stopped (SIGTERM, so the requests in hand finish) with the app.
    serve.add_argument("--die-with-parent", action="store_true", help=argparse.SUPPRESS)


def run(args: argparse.Namespace) -> int:
    # Starlette, uvicorn and jinja2: only for serve, never for the app's start-up.
    from racer_tui.web.server import serve  # noqa: PLC0415 (the web server: only for serve)

    if not 0 <= args.port <= 65535:
        raise RemedyError(f"--port must be from 0 to 65535, not {args.port}.")
    if args.die_with_parent:
        die_with_parent(os.getppid(), signal.SIGTERM)
    db_path = args.db if args.db is not None else default_db_path()
    # uvicorn stops on Ctrl+C (or SIGTERM) itself, after the requests in hand.
    serve(db_path, args.host, args.port, args.night, say=lambda line: print(line, flush=True))
    return 0
