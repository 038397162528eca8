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
import sys

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


def print_urls(view: Hosted, file=sys.stderr) -> None:
    print("simatch: web UI (each address carries that page's token; keep them to yourself):", file=file)
    for label, url in view.urls.items():
        print(f"  {label:14s} {url}", file=file)
    file.flush()


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

    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group(self.group)
        group.add_argument("--view", action="store_true", help=self.help)
        add_view_options(group)

    def start(self, target, args) -> Hosted:
        raise NotImplementedError

    @contextlib.contextmanager
    def attach(self, target, args):
        if not getattr(args, "view", False):
            yield None
            return
        with self.start(target, args) as view:
            print_urls(view)
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

    def start(self, player, args) -> Hosted:
        return start_recording_view(player, args.view_host, args.view_port)
