"""`racer-tui serve`: the league on the web, read-only.

A small ASGI app (Starlette, served by uvicorn) over the league database: the leaderboard,
a league night and its heat running now (`live`) as pages a venue's projector and the
audience's phones open, and the same as JSON for a league's own site or bot
(`docs/hosts/web.md`). It answers GET (and
HEAD) alone and opens the database read-only, so nothing anyone sends can change the
league. Every string it shows came from racers' machines by sync and is escaped by the
template engine (the live page's script sets them as text); the pages load nothing from
elsewhere (a venue may be offline), under a Content-Security-Policy that allows only this
server's own stylesheet, script and event stream.

Nothing here is imported by the app's start-up or the headless race path: the command
line imports it only for `serve`.
"""
