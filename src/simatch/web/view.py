"""``--view``: the run extension that serves the web UI while ``simatch run`` runs a scene.

It prints the address of every page with its token, waits for a first page to open (so that nobody
misses the start; ``--view-wait`` limits the wait), runs the scene at real time while a live page is
open, and after the end keeps serving — the replay page can go through the whole run — until the last
page is closed.
"""

from __future__ import annotations

import argparse
import contextlib
import sys

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
    group.add_argument("--view-host", default="127.0.0.1", metavar="HOST",
                       help="address to serve the web UI on (default 127.0.0.1, this machine only)")
    group.add_argument("--view-port", type=port_number, default=DEFAULT_PORT, metavar="PORT",
                       help=f"port of the web UI (default {DEFAULT_PORT}; 0: any free port)")
    group.add_argument("--view-wait", type=float, default=default_wait, metavar="S",
                       help="wait at most S seconds for a page to open before the run starts "
                            "(default: until one opens)")


def start_view(sim, host: str, port: int) -> LiveView:
    """A started LiveView; a port that cannot be had is a usage error (no traceback)."""
    from ..cli import UsageError

    try:
        return LiveView(sim, host=host, port=port).start()
    except OSError as exc:
        raise UsageError(str(exc)) from None


def print_urls(view: LiveView, file=sys.stderr) -> None:
    print("simatch: web UI (each address carries that page's token; keep them to yourself):", file=file)
    for label, url in view.urls.items():
        print(f"  {label:14s} {url}", file=file)
    file.flush()


class ViewExtension:
    """Registered in ``simatch.cli.run.EXTENSIONS``."""

    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group("live view (web UI)")
        group.add_argument("--view", action="store_true",
                           help="serve the coach pages, the referee console and the replay page while the "
                                "scene runs; the run goes at real time while a page is open")
        add_view_options(group)

    @contextlib.contextmanager
    def attach(self, sim, args):
        if not getattr(args, "view", False):
            yield None
            return
        with start_view(sim, args.view_host, args.view_port) as view:
            print_urls(view)
            if args.view_wait is None or args.view_wait > 0:
                print("simatch: waiting for a page to open (Ctrl-C to give up)...", file=sys.stderr, flush=True)
                view.wait_for_viewer(args.view_wait)
            yield view
            if view.server.live_viewers:
                print("simatch: the run has ended; its pages stay up until they are all closed (Ctrl-C to quit)",
                      file=sys.stderr, flush=True)
            view.finish()
