"""``--view``: the extensions that serve the web UI while ``simatch run`` runs a scene (`ViewExtension`) and
while ``simatch replay`` plays a recording back (`ReplayViewExtension`).

Both print the address of every page with its token and wait for a first page to open (so that nobody
misses the start; ``--view-wait`` limits the wait). A run goes at real time while a live page is open; a
recording plays at its ``--speed``. After the end the server keeps serving — the replay page can go through
the whole run — until the last page is closed.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import threading
import webbrowser

from .hosting import Hosted
from .live import LiveView

DEFAULT_PORT = 8765


def port_number(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"port {port} is not between 0 and 65535")
    return port


def add_view_options(group, default_wait: float | None = None) -> None:
    group.add_argument(
        "--view-host",
        default="127.0.0.1",
        metavar="HOST",
        help="address to serve the web UI on (default 127.0.0.1, this machine only)",
    )
    group.add_argument(
        "--view-port",
        type=port_number,
        default=DEFAULT_PORT,
        metavar="PORT",
        help=f"port of the web UI (default {DEFAULT_PORT}; 0: any free port)",
    )
    group.add_argument(
        "--view-wait",
        type=float,
        default=default_wait,
        metavar="S",
        help="wait at most S seconds for a page to open before the run starts (default: until one opens)",
    )
    group.add_argument(
        "--open",
        dest="open_page",
        action="store_const",
        const="first",
        help="open the referee console (for a recording: the replay page) in this machine's web browser",
    )
    group.add_argument(
        "--open-3d",
        dest="open_page",
        action="store_const",
        const="3d view",
        help="open the 3D view in this machine's web browser",
    )


def _started(make) -> Hosted:
    """A started view; a port that cannot be had (or a recording that cannot be shown) is a usage error."""
    from ..errors import UsageError
    from .recorded import RecordingError

    try:
        return make().start()
    except (OSError, RecordingError) as exc:
        raise UsageError(str(exc)) from None


def start_view(sim, host: str, port: int) -> LiveView:
    """A started LiveView of ``sim``."""
    return _started(lambda: LiveView(sim, host=host, port=port))


def start_recording_view(player, host: str, port: int):
    """A started RecordingView of ``player`` (a `simatch.record.player.Player`)."""
    from .recorded import RecordingView

    return _started(lambda: RecordingView(player, host=host, port=port))


def print_urls(view: Hosted, file=sys.stderr, first: str = "referee", opened: bool = False) -> None:
    """The pages' addresses, set apart from what comes before and after (a progress bar, the summary), the page
    to open first at the top."""
    urls = view.urls
    order = [first] + [label for label in urls if label != first] if first in urls else list(urls)
    rule = "-" * 79
    print(f"\n{rule}", file=file)
    print(f"simatch: web UI: open the {_page_name(first)} in a browser to watch", file=file)
    print("(each address carries its page's token: keep them to yourself)", file=file)
    for label in order:
        print(f"  {label:14s} {urls[label]}", file=file)
    if not opened:
        print(f"  (--open opens the {_page_name(first)} in this machine's browser, --open-3d the 3D view)", file=file)
    print(rule, file=file)
    file.flush()


def _page_name(label: str) -> str:
    return {"referee": "referee console", "replay": "replay page", "3d view": "3D view"}.get(label, f"{label} page")


def open_in_browser(url: str, file=sys.stderr) -> bool:
    """Open ``url`` in the user's web browser (Python's `webbrowser`, which honours $BROWSER), in a thread of its
    own: a browser command that runs until the browser is closed must not hold the run up. Where there is no
    graphical browser (no display, no $BROWSER) nothing is started (a text browser would take over this
    terminal): the address printed above is the way in."""
    graphical = (
        os.environ.get("BROWSER")
        or sys.platform in ("darwin", "win32")
        or os.environ.get("DISPLAY")
        or os.environ.get("WAYLAND_DISPLAY")
    )
    if not graphical:
        print("simatch: --open: no graphical browser here (no display, no $BROWSER): open the address above", file=file)
        return False

    def opening() -> None:
        try:
            if not webbrowser.open(url, new=2):
                print("simatch: --open: no browser could be started: open the address above", file=file)
        except webbrowser.Error as exc:
            print(f"simatch: --open: {exc}: open the address above", file=file)

    threading.Thread(target=opening, name="simatch-open-browser", daemon=True).start()
    return True


def announce(view: Hosted, args, first: str = "referee") -> None:
    """Print the addresses and, with --open, open the first page (--open-3d: the 3D view) in the browser."""
    which = getattr(args, "open_page", None)
    print_urls(view, first=first, opened=which is not None)
    if which is not None:
        open_in_browser(view.urls[first if which == "first" else which])


def wait_for_page(view: Hosted, wait: float | None, any_page: bool = False) -> None:
    if wait is None or wait > 0:
        print("simatch: waiting for a page to open (Ctrl-C to give up)...", file=sys.stderr, flush=True)
        view.wait_for_viewer(wait, any_page=any_page)


def linger(view: Hosted, what: str) -> None:
    if view.server.clients:
        print(
            f"simatch: {what} has ended; its pages stay up until they are all closed (Ctrl-C to quit)",
            file=sys.stderr,
            flush=True,
        )
    view.finish()


class _ViewOption:
    """The ``--view`` option of a command: it adds the options and wraps what the command runs."""

    group = "web UI"
    help = ""
    what = "the run"  # what has ended, in the last message
    any_page = False  # whether a replay page alone is a viewer to wait for
    first = "referee"  # the page to open first

    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group(self.group)
        group.add_argument("--view", action="store_true", help=self.help)
        add_view_options(group)

    def start(self, target, args) -> Hosted:
        raise NotImplementedError

    @contextlib.contextmanager
    def attach(self, target, args):
        if not getattr(args, "view", False):
            if getattr(args, "open_page", None) is not None:
                from ..errors import UsageError

                raise UsageError("--open (or --open-3d) opens a page of the web UI: it goes with --view")
            yield None
            return
        with self.start(target, args) as view:
            announce(view, args, first=self.first)
            wait_for_page(view, args.view_wait, any_page=self.any_page)
            yield view
            linger(view, self.what)


class ViewExtension(_ViewOption):
    """Registered in ``simatch.cli.run.EXTENSIONS``: ``simatch run SCENE --view``."""

    group = "live view (web UI)"
    help = (
        "serve the coach pages, the referee console and the replay page while the scene runs; the run goes "
        "at real time while a page is open"
    )

    def start(self, sim, args) -> Hosted:
        return start_view(sim, args.view_host, args.view_port)


class ReplayViewExtension(_ViewOption):
    """Registered in ``simatch.cli.replay.EXTENSIONS``: ``simatch replay FILE.mcap --view``."""

    help = (
        "serve the web UI while the recording plays: the coach pages and the referee console watch the "
        "replayed bus, the replay page goes through the whole recording (play, pause, speed, seek)"
    )
    what = "the playback"
    any_page = True
    first = "replay"

    def start(self, player, args) -> Hosted:
        return start_recording_view(player, args.view_host, args.view_port)
