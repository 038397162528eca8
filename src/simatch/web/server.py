"""The web server: pages over HTTP and one WebSocket per open page, in a thread of its own.

aiohttp serves both on one port (loopback by default) from an asyncio loop in a background thread, so
the simulation in the main thread never waits for a viewer. A ticker builds the live pictures about 30
times a second — once per kind of page, whatever the number of viewers — and every page's sender
sends the newest one: a slow viewer skips frames instead of delaying the others or the run.

Live pictures are drawn a little behind the newest simulated time (at most `LAG` seconds): a run paced at
real time advances in bursts, and drawing from the recorded timeline at a steady wall-clock rate turns
those bursts into smooth motion.
"""

from __future__ import annotations

import asyncio
import bisect
import json
import logging
import socket
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources

from aiohttp import WSMsgType, web

from . import protocol as P
from .access import Access, Grant
from .observer import RunObserver
from .picture import Picture

log = logging.getLogger(__name__)

PAGES = {"referee": "referee.html", "replay": "replay.html", "coach": "coach.html", "view3d": "view3d.html"}
LAG = 0.25  # [s] the live picture trails the newest state by at most this
EVENT_BACKLOG = 300  # events a page gets when it (re)connects
RECENT_EVENTS = 12  # events a replay frame carries (those before its time)


@dataclass
class ReplayCursor:
    """One replay page's own position on the timeline."""

    t: float = 0.0
    speed: float = 1.0
    playing: bool = True

    def apply(self, m: P.Timeline, start: float, end: float, follow: float | None = None) -> None:
        """Carry out a timeline request; ``live`` jumps to ``follow`` (the moment the live pages show) or,
        without live pages, to the end."""
        if m.action == "play":
            if self.t >= end:
                self.t = start
            self.playing = True
        elif m.action == "pause":
            self.playing = False
        elif m.action == "seek":
            self.t = min(max(m.value, start), end)
        elif m.action == "live":
            t = end if follow is None else follow
            self.t, self.playing, self.speed = min(max(t, start), end), True, 1.0
        elif m.action == "speed":
            if not 0.05 <= m.value <= 32.0:
                raise P.ProtocolError("speed must be between 0.05 and 32")
            self.speed = m.value

    def advance(self, dt: float, start: float, end: float, growing: bool) -> None:
        if self.playing:
            self.t = min(self.t + dt * self.speed, end)
            if self.t >= end and not growing:
                self.playing = False
        self.t = max(self.t, start)


@dataclass
class Archive:
    """What the replay pages go through: the timeline of the run (its last hour) and its pictures — the live run's
    own observer, or one loaded from a recording (``complete`` says when it stops growing)."""

    observer: RunObserver
    picture: Picture
    complete: Callable[[], bool]


@dataclass(eq=False)
class Client:
    ws: web.WebSocketResponse
    grant: Grant
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    events_sent: int = -1
    frames_sent: int = 0
    cursor: ReplayCursor | None = None

    @property
    def live(self) -> bool:
        """A page that watches the run as it happens (it paces the run): all but the replay page. The 3D view
        is one even while it looks back over its own timeline (``cursor``), as its viewer is watching."""
        return self.grant.role != "replay"

    @property
    def following(self) -> bool:
        """The page shows the live picture (the one built for all pages of its kind), not its own timeline's."""
        return self.cursor is None

    @property
    def kind(self) -> tuple[str, str]:
        """Which live picture the page shows: its team's (a coach page) or the world's."""
        return (self.grant.role, self.grant.team)


class ViewServer:
    """Serves the pages of one run. ``control`` carries out commands (None: a run that cannot be
    commanded from here, e.g. a recording, and ``read_only`` says why); ``archive`` is what replay pages go
    through (default: the live observer's timeline); ``on_viewers(n)`` hears how many live pages are open."""

    def __init__(
        self,
        observer: RunObserver,
        picture: Picture,
        access: Access,
        hello: dict,
        control=None,
        host: str = "127.0.0.1",
        port: int = 8765,
        fps: float = 40.0,
        on_viewers: Callable[[int], None] | None = None,
        archive: Archive | None = None,
        read_only: str = "this server shows a run it does not command",
    ):
        self.observer = observer
        self.picture = picture
        self.access = access
        self.hello = hello
        self.control = control
        self.read_only = read_only
        self.archive = archive or Archive(observer, picture, lambda: self.status == "ended")
        self.host, self.port = host, port
        self.fps = fps
        self.on_viewers = on_viewers
        self.status = "running"  # "waiting", "running" or "ended": the pages show it
        self.clients: set[Client] = set()
        self.live_t: float | None = None
        self._live: dict[tuple[str, str], str] = {}
        self._seq = 0
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    # --- life cycle (main thread) ------------------------------------------------------------------------
    def start(self) -> None:
        """Bind and serve (again, after `stop`: the same port, so open pages reconnect by themselves)."""
        self._ready.clear()
        self._error = None
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((self.host, self.port))
        except OSError as exc:
            sock.close()
            raise OSError(
                f"cannot serve the web UI on {self.host}:{self.port}: {exc.strerror} "
                f"(choose another port with --view-port, 0 for any free one)"
            ) from None
        sock.listen(64)
        sock.setblocking(False)
        self.port = sock.getsockname()[1]
        self._sock = sock
        self._thread = threading.Thread(target=self._main, name="simatch-web", daemon=True)
        self._thread.start()
        self._ready.wait(15.0)
        if self._error is not None:
            raise RuntimeError(f"the web server did not start: {self._error}")

    @property
    def base_url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}"

    def urls(self) -> dict[str, str]:
        return self.access.urls(self.base_url)

    @property
    def live_viewers(self) -> int:
        return sum(1 for c in list(self.clients) if c.live)

    def stop(self) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(self._stopping.set)
            except RuntimeError:
                pass
        if self._thread is not None:
            self._thread.join(10.0)
            self._thread = None

    # --- the server's thread -------------------------------------------------------------------------------
    def _main(self) -> None:
        loop = asyncio.new_event_loop()
        self._loop = loop
        try:
            loop.run_until_complete(self._serve())
        except BaseException as exc:  # reported to start(); the run goes on without a viewer
            self._error = exc
            log.exception("the web server stopped")
        finally:
            self._ready.set()
            loop.close()

    async def _serve(self) -> None:
        self._stopping = asyncio.Event()
        app = web.Application(client_max_size=64 * 1024)
        app.on_response_prepare.append(_headers)
        static = resources.files(__package__).joinpath("static")
        self._static = static
        app.router.add_get("/", self._page("index.html"))
        app.router.add_get("/referee", self._page(PAGES["referee"]))
        app.router.add_get("/replay", self._page(PAGES["replay"]))
        app.router.add_get("/view3d", self._page(PAGES["view3d"]))
        app.router.add_get("/coach/{team}", self._coach_page)
        app.router.add_get("/ws", self._ws)
        app.router.add_get("/favicon.ico", _no_content)
        app.router.add_static("/static", str(static), show_index=False, follow_symlinks=False)
        runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=1.0)
        await runner.setup()
        await web.SockSite(runner, self._sock).start()
        ticker = asyncio.create_task(self._ticker())
        self._ready.set()
        try:
            await self._stopping.wait()
        finally:
            ticker.cancel()
            for c in list(self.clients):
                await c.ws.close(code=1001, message=b"server stopping")
            await runner.cleanup()

    def _page(self, filename: str):
        async def handler(request):
            return web.FileResponse(str(self._static.joinpath(filename)))

        return handler

    async def _coach_page(self, request):
        if request.match_info["team"] not in self.picture.teams:
            raise web.HTTPNotFound(text=f"this run has no team {request.match_info['team']!r}")
        return web.FileResponse(str(self._static.joinpath(PAGES["coach"])))

    # --- pictures --------------------------------------------------------------------------------------------
    async def _ticker(self) -> None:
        loop = asyncio.get_running_loop()
        period = 1.0 / self.fps
        last = due = loop.time()
        while True:
            due += period  # a fixed schedule: sleeping late does not drift the rate
            now = loop.time()
            if due < now - period:
                due = now
            await asyncio.sleep(max(0.0, due - now))
            now = loop.time()
            dt, last = now - last, now
            try:
                self._advance_live(dt)
                self._build_live()
            except Exception:  # a picture that fails must not stop the others
                log.exception("building a live picture failed")
            for c in list(self.clients):
                c.wake.set()

    def _advance_live(self, dt: float) -> None:
        tl = self.observer.timeline
        if tl is None or tl.count == 0:
            return
        newest = tl.end
        t = self.live_t
        if t is None or t < newest - LAG or t > newest:
            t = newest - 0.5 * LAG if t is None or t < newest - LAG else newest
        else:
            t = min(t + dt, newest)
        self.live_t = max(t, tl.start)

    def _build_live(self) -> None:
        tl = self.observer.timeline
        if self.live_t is None or tl is None:
            return
        wanted = {c.kind for c in list(self.clients) if c.live and c.following}
        frames = {}
        world = None
        for role, team in wanted:
            if role == "coach":
                pic = self.picture.team(team, self.live_t)
            else:
                world = world or self.picture.world(tl.index_at(self.live_t), live=True)
                pic = dict(world)
            if role == "view3d":
                pic["timeline"] = self._history(tl)
            pic["status"] = self.status
            frames[(role, team)] = json.dumps(pic, separators=(",", ":"))
        self._live = frames
        self._seq += 1

    def _history(self, tl) -> dict:
        """Where the live picture stands in what can be looked back over (the 3D view's timeline)."""
        archive = self.archive.observer.timeline
        start, end = (archive.start, archive.end) if archive is not None else (tl.start, tl.end)
        t = round(self.live_t, 3)
        return {
            "start": round(start, 3),
            "end": round(end, 3),
            "t": t,
            "speed": 1.0,
            "playing": True,
            "complete": self.archive.complete(),
            "follow": t,
            "live": True,
        }

    def _replay_frame(self, c: Client, dt: float) -> str | None:
        archive = self.archive
        tl = archive.observer.timeline
        if tl is None or tl.count == 0:
            return None
        cur = c.cursor
        complete = archive.complete()
        cur.advance(dt, tl.start, tl.end, growing=not complete)
        pic = archive.picture.world(tl.index_at(cur.t))
        events = archive.observer.events
        n = bisect.bisect_right(events, cur.t + 1e-6, key=lambda e: e["t"])
        recent = events[max(0, n - RECENT_EVENTS) : n]
        pic.update(
            status=self.status,
            events=recent,
            timeline={
                "start": round(tl.start, 3),
                "end": round(tl.end, 3),
                "t": round(cur.t, 3),
                "speed": cur.speed,
                "playing": cur.playing,
                "complete": complete,
                "follow": None if self.live_t is None else round(self.live_t, 3),
                "live": False,
            },
        )
        return json.dumps(pic, separators=(",", ":"))

    def _timeline(self, c: Client, m: P.Timeline) -> None:
        """Move a page's own timeline. A live page (the 3D view) that leaves the live picture gets a timeline
        of its own, starting where the live picture is; ``live`` gives it back the live picture."""
        tl = self.archive.observer.timeline
        start, end = (tl.start, tl.end) if tl is not None else (0.0, 0.0)
        if c.live and m.action == "live":
            c.cursor = None
        else:
            if c.cursor is None:
                c.cursor = ReplayCursor(t=min(max(self.live_t if self.live_t is not None else end, start), end))
            c.cursor.apply(m, start, end, follow=self.live_t)
        c.wake.set()

    # --- one page --------------------------------------------------------------------------------------------
    async def _ws(self, request):
        ws = web.WebSocketResponse(heartbeat=15.0, max_msg_size=4 * P.MAX_MESSAGE_BYTES)
        await ws.prepare(request)
        grant = self.access.grant(request.query.get("token"))
        if grant is None:
            await ws.send_json(
                {
                    "type": "error",
                    "fatal": True,
                    "error": "unknown or missing token: open an address printed on the console",
                }
            )
            await ws.close(code=4001, message=b"unknown token")
            return ws
        c = Client(ws, grant)
        if grant.role == "replay":
            tl = self.archive.observer.timeline
            c.cursor = ReplayCursor(t=tl.start if tl is not None else 0.0)
        self.clients.add(c)
        self._viewers_changed()
        sender = asyncio.create_task(self._send_loop(c))
        try:
            hello = dict(
                self.hello,
                type="hello",
                role=grant.role,
                team=grant.team,
                status=self.status,
                capabilities=self.control.capabilities(grant) if self.control is not None else None,
                links=self._links(grant),
            )
            await ws.send_str(json.dumps(hello))
            c.wake.set()
            async for msg in ws:
                if msg.type == WSMsgType.TEXT:
                    await self._on_message(c, msg.data)
                elif msg.type == WSMsgType.BINARY:
                    await self._send_error(c, None, "messages are JSON text, not binary")
        finally:
            sender.cancel()
            self.clients.discard(c)
            self._viewers_changed()
        return ws

    def _links(self, grant: Grant) -> dict[str, str]:
        """The other pages a page links to: the 3D view, with its token for the pages that see the exact world
        already (the referee console, the replay page); a coach page sees only what its team perceives, so its
        link opens the 3D view with the address printed on the console."""
        sees_all = grant.role in ("referee", "replay", "view3d")
        return {"3d view": f"/view3d?token={self.access.token('view3d')}" if sees_all else "/view3d"}

    def _viewers_changed(self) -> None:
        if self.on_viewers is not None:
            try:
                self.on_viewers(self.live_viewers)
            except Exception:
                log.exception("on_viewers failed")

    async def _send_loop(self, c: Client) -> None:
        loop = asyncio.get_running_loop()
        last = loop.time()
        seq = -1
        try:
            while not c.ws.closed:
                await c.wake.wait()
                c.wake.clear()
                now = loop.time()
                dt, last = now - last, now
                if c.live and c.following:
                    key = c.kind
                    if self._seq != seq and key in self._live:
                        seq = self._seq
                        await c.ws.send_str(self._live[key])
                        c.frames_sent += 1
                    await self._send_events(c)
                else:
                    frame = self._replay_frame(c, dt)
                    if frame is not None:
                        await c.ws.send_str(frame)
                        c.frames_sent += 1
        except (ConnectionError, RuntimeError, asyncio.CancelledError):
            pass

    async def _send_events(self, c: Client) -> None:
        events = self.observer.events
        n = len(events)
        if c.events_sent < 0:
            start = max(0, n - EVENT_BACKLOG)
            await c.ws.send_str(json.dumps({"type": "events", "reset": True, "items": events[start:n]}))
            c.events_sent = n
        elif n > c.events_sent:
            await c.ws.send_str(json.dumps({"type": "events", "items": events[c.events_sent : n]}))
            c.events_sent = n

    async def _on_message(self, c: Client, text: str) -> None:
        mid = P.message_id(text)
        try:
            m = P.parse(text, c.grant.role)
            P.authorize(m, c.grant.role, c.grant.team)
            if isinstance(m, P.Timeline):
                self._timeline(c, m)
                error = None
            elif self.control is None:
                error = self.read_only
            else:
                error = await self._submit(c.grant, m)
        except P.ProtocolError as exc:
            error = str(exc)
        if error is None:
            if mid is not None:
                await c.ws.send_json({"type": "ack", "id": mid})
        else:
            await self._send_error(c, mid, error)

    async def _submit(self, grant: Grant, m) -> str | None:
        loop = asyncio.get_running_loop()
        done: asyncio.Future = loop.create_future()

        def reply(error: str | None) -> None:  # called in the simulation's thread
            def settle() -> None:
                if not done.done():
                    done.set_result(error)

            try:
                loop.call_soon_threadsafe(settle)
            except RuntimeError:  # the server is already gone
                pass

        self.control.submit(grant, m, reply)
        try:
            return await asyncio.wait_for(done, timeout=5.0)
        except TimeoutError:
            return "the run did not take the request within 5 s (it is not running)"

    async def _send_error(self, c: Client, mid, error: str) -> None:
        out = {"type": "error", "error": error}
        if mid is not None:
            out["id"] = mid
        try:
            await c.ws.send_json(out)
        except ConnectionError:
            pass


async def _no_content(request) -> web.Response:
    return web.Response(status=204)


async def _headers(request, response) -> None:
    """Tokens travel in page addresses: never leak them in a Referer, never let a page be framed."""
    response.headers["Referrer-Policy"] = "no-referrer"
    response.headers["X-Frame-Options"] = "DENY"
    response.headers["X-Content-Type-Options"] = "nosniff"
    response.headers["Cache-Control"] = "no-store"
