"""The web server: routes, the read-only league connection, the security headers, and
`serve`, which binds the address and runs uvicorn until Ctrl+C."""

from __future__ import annotations

import ipaddress
import json
import socket
import sqlite3
import time
from collections.abc import Callable, Mapping
from contextlib import closing
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import quote

import uvicorn
from jinja2 import Environment, PackageLoader
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Route
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from league.errors import LeagueError
from league.live_heat import live_heat_path, read_live_heat
from league.nights import Night
from league.opening import BUSY_TIMEOUT_MS, open_league
from league.race_types import words as race_type_words
from league.report import SCORE_TITLES
from league.store import League
from racer_tui.web.live import Leader, LiveFeed, night_leader, track_map
from racer_tui.web.pages import (
    Leaderboard,
    league_leaderboard,
    night_document,
    ranking_for,
    shown_night,
)
from sim.physics.labels import describe as physics_words
from sim.race.rules import RankingMethod
from sim.training.drivers import DriversByHash

# Only this server's own stylesheet and script, and its own event stream: no inline
# script, no frame, no form, nothing from elsewhere.
CONTENT_SECURITY_POLICY = (
    "default-src 'none'; style-src 'self'; script-src 'self'; connect-src 'self'; "
    "img-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"
)
SECURITY_HEADERS: Mapping[str, str] = {
    "content-security-policy": CONTENT_SECURITY_POLICY,
    "x-content-type-options": "nosniff",
    "referrer-policy": "no-referrer",
    "cache-control": "no-store",  # every page is the league as it is now
}
# The leaderboard and night pages reload themselves this often (a projector has no one to
# press F5); the live heat will be pushed instead.
REFRESH_SECONDS = 10
T = TypeVar("T")
GARAGE_SECONDS = 30.0
GRACEFUL_SECONDS = 2
STYLESHEET = "site.css"
SCRIPT = "live.js"  # the live page's only script: it fills the page from the event stream


class SecurityHeaders:
    """Add `SECURITY_HEADERS` to every response, errors included."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                names = {name.lower() for name, _ in headers}
                for name, value in SECURITY_HEADERS.items():
                    if name.encode() not in names:
                        headers.append((name.encode(), value.encode()))
                message["headers"] = headers
            await send(message)

        await self.app(scope, receive, with_headers)


def read_only_league(path: Path) -> League:
    """The league database opened so that no statement can write: SQLite's read-only
    mode, and `query_only` on top of it."""
    uri = f"file:{quote(str(path.resolve()))}?mode=ro"
    conn = sqlite3.connect(uri, uri=True, timeout=BUSY_TIMEOUT_MS / 1000)
    conn.row_factory = sqlite3.Row
    conn.execute("PRAGMA query_only = ON")
    return League(path, conn)


def _templates() -> Environment:
    environment = Environment(
        loader=PackageLoader("racer_tui.web", "templates"),
        autoescape=True,  # every string on a page is text, whatever a racer named things
        trim_blocks=True,
        lstrip_blocks=True,
    )
    environment.filters["seconds"] = _seconds
    environment.filters["race_type_words"] = race_type_words
    environment.filters["physics_words"] = physics_words
    return environment


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def create_web_app(db_path: Path, night: str | None = None) -> Starlette:
    """The league at `db_path` on the web; `night`: the night `/night` shows (else the
    newest open one)."""
    templates = _templates()
    stylesheet = (Path(__file__).parent / "static" / STYLESHEET).read_bytes()
    live_script = (Path(__file__).parent / "static" / SCRIPT).read_bytes()

    garage: list[tuple[float, frozenset[str]]] = []  # (when, hashes): read at most so often

    def models_here() -> frozenset[str]:
        """The garage's model hashes (their results are verifiable here). Hashing every
        model's files takes a while: a page a phone reloads every 10 s must not do it each
        time, so they are read again at most every `GARAGE_SECONDS`."""
        now = time.monotonic()
        if not garage or now - garage[0][0] > GARAGE_SECONDS:
            garage[:] = [(now, DriversByHash().models_here())]
        return garage[0][1]

    def answer(request: Request, work: Callable[[League, frozenset[str]], T]) -> T | Response:
        """`work` on the league opened read-only, with the garage's model hashes; a bad
        request or an unreadable league in a sentence."""
        try:
            with closing(read_only_league(db_path)) as league:
                return work(league, models_here())
        except LeagueError as error:
            return _problem(request, str(error), 404)
        except sqlite3.Error as error:
            return _problem(request, f"the league database cannot be read ({error}).", 503)

    def _problem(request: Request, sentence: str, status: int) -> Response:
        if request.url.path.startswith("/api/"):
            return JSONResponse({"error": sentence}, status_code=status)
        html = templates.get_template("problem.html").render(sentence=sentence, css=STYLESHEET)
        return HTMLResponse(html, status_code=status)

    def render(name: str, **values: Any) -> HTMLResponse:
        values.setdefault("refresh", REFRESH_SECONDS)
        page = templates.get_template(name).render(css=STYLESHEET, script=SCRIPT, **values)
        return HTMLResponse(page)

    def leaderboard(request: Request, respond: Callable[[Leaderboard], Response]) -> Response:
        """The league's boards ranked as `?by=` asks (a bad word: 400), answered by `respond`."""
        by = request.query_params.get("by")
        try:
            ranking_for(by)
        except LeagueError as error:
            return _problem(request, str(error), 400)
        return answer(request, lambda league, here: respond(league_leaderboard(league, by, here)))

    def leaderboard_html(request: Request) -> Response:
        return leaderboard(request, lambda board: render("leaderboard.html", board=board))

    def leaderboard_api(request: Request) -> Response:
        return leaderboard(request, lambda board: JSONResponse(board.to_json()))

    def night_html(request: Request) -> Response:
        def page(league: League, here: frozenset[str]) -> Response:
            found = shown_night(league, request.query_params.get("id") or night)
            if found is None:
                return render("night.html", night=None)
            ranking = found.rules.ranking
            running = read_live_heat(live_heat_path(db_path, found.id), found.id)
            document = night_document(league, found, here)
            drawn = document["bracket"]
            return render(
                "night.html",
                night=document,
                bracket=drawn,
                matches={match["id"]: match for match in drawn["matches"]} if drawn else {},
                running_heat=running.heat_number if running is not None else None,
                # A best lap is a column already: the score needs its own only otherwise.
                score_column=ranking is not RankingMethod.BEST_LAP,
                score_title=SCORE_TITLES[ranking],
            )

        return answer(request, page)

    def night_api(request: Request) -> Response:
        def document(league: League, here: frozenset[str]) -> Response:
            found = shown_night(league, request.query_params.get("id") or night)
            if found is None:
                raise LeagueError("this league has no night yet.")
            return JSONResponse(night_document(league, found, here))

        return answer(request, document)

    def css(request: Request) -> Response:
        return Response(stylesheet, media_type="text/css")

    def script(request: Request) -> Response:
        return Response(live_script, media_type="text/javascript")

    feeds: dict[str, LiveFeed] = {}

    def feed_for(found: Night) -> LiveFeed:
        feed = feeds.get(found.id)
        if feed is None:

            def leader() -> Leader | None:
                with closing(read_only_league(db_path)) as league:
                    return night_leader(league, found, models_here())

            feed = LiveFeed(db_path, found, leader, track_map(found.track_hash))
            feeds[found.id] = feed
        return feed

    async def live_feed(request: Request) -> LiveFeed | Response:
        """The feed of the night `?id=` names (else the served one); a problem's answer."""

        def find(league: League, here: frozenset[str]) -> Night:
            found = shown_night(league, request.query_params.get("id") or night)
            if found is None:
                raise LeagueError("this league has no night yet.")
            return found

        answered = await run_in_threadpool(answer, request, find)
        if isinstance(answered, Response):
            return answered
        feed = feed_for(answered)
        await feed.refresh()
        return feed

    async def live_html(request: Request) -> Response:
        feed = await live_feed(request)
        if isinstance(feed, Response):
            return feed
        return render("live.html", live=json.loads(feed.payload), map=feed.drawing, refresh=0)

    async def overlay_html(request: Request) -> Response:
        feed = await live_feed(request)
        if isinstance(feed, Response):
            return feed
        return render("overlay.html", live=json.loads(feed.payload), refresh=0)

    async def live_api(request: Request) -> Response:
        feed = await live_feed(request)
        if isinstance(feed, Response):
            return feed
        return Response(feed.payload, media_type="application/json")

    async def live_stream(request: Request) -> Response:
        feed = await live_feed(request)
        if isinstance(feed, Response):
            return feed
        return StreamingResponse(
            feed.events(),
            media_type="text/event-stream",
            headers={"x-accel-buffering": "no"},  # a proxy in front passes each event on
        )

    routes = [
        Route("/", leaderboard_html, methods=["GET"]),
        Route("/night", night_html, methods=["GET"]),
        Route("/api/leaderboard", leaderboard_api, methods=["GET"]),
        Route("/api/night", night_api, methods=["GET"]),
        Route("/live", live_html, methods=["GET"]),
        Route("/overlay", overlay_html, methods=["GET"]),
        Route("/api/live", live_api, methods=["GET"]),
        Route("/api/live/stream", live_stream, methods=["GET"]),
        Route(f"/{STYLESHEET}", css, methods=["GET"]),
        Route(f"/{SCRIPT}", script, methods=["GET"]),
    ]
    app = Starlette(routes=routes)
    app.add_middleware(SecurityHeaders)
    return app


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def bind(host: str, port: int) -> socket.socket:
    """The listening socket; LeagueError in a sentence when the address cannot be had."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror:
        raise LeagueError(
            f"{host!r} is not an address of this machine; give --host an IP address."
        ) from None
    family, kind, proto, _, address = infos[0]
    listener = socket.socket(family, kind, proto)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        listener.bind(address)
    except OSError as error:
        listener.close()
        raise LeagueError(
            f"cannot listen on {host} port {port} ({error.strerror}); choose another with --port."
        ) from None
    listener.listen(128)
    return listener


def serve(
    db_path: Path, host: str, port: int, night: str | None, say: Callable[[str], None]
) -> None:
    """Serve the league at `db_path` until interrupted; `say` the address first."""
    with open_league(db_path) as league:  # created and migrated now: the server only reads
        if night:
            shown_night(league, night)  # a night that does not exist, said before serving
    app = create_web_app(db_path, night)
    listener = bind(host, port)
    bound_host, bound_port = listener.getsockname()[:2]
    shown = f"[{bound_host}]" if ":" in bound_host else bound_host
    who = (
        "only this machine can open it"
        if is_loopback(bound_host)
        else "anyone who can reach this machine on the network can open it"
    )
    say(
        f"Serving the league {db_path} read-only at http://{shown}:{bound_port}/ "
        f"({who}); the night at /night, JSON at /api/leaderboard and /api/night. "
        "Ctrl+C stops it."
    )
    config = uvicorn.Config(
        app,
        log_level="warning",
        access_log=False,
        server_header=False,
        lifespan="off",
        # A live page's stream never ends by itself: on Ctrl+C (or when the app that
        # started it quits) the server waits this long for the requests in hand, no more.
        timeout_graceful_shutdown=GRACEFUL_SECONDS,
    )
    uvicorn.Server(config).run(sockets=[listener])
