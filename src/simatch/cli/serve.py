"""``simatch serve SCENE``: a standing match server for the web UI.

Unlike ``simatch run --view`` (a run that is also shown), the scene here exists to be watched and
commanded from the pages: it advances at real time while at least one coach page or the referee
console is open and waits while none is, until the judge ends it, ``--duration`` is reached or Ctrl-C.
Then the pages stay up (the replay page goes through the whole match) until they are all closed.
"""

from __future__ import annotations

import json
import sys
import time

from ..scene.loader import load_scene
from .run import add_run_options, overrides_of, print_summary

CHUNK = 0.05        # [s] simulated between two looks at the open pages


def add_parser(sub) -> None:
    from ..web.view import add_view_options

    p = sub.add_parser("serve", help="serve a scene to the web UI (coach pages, referee console, replay)",
                       description="Run a scene for the web UI: the coach page of each team, the referee "
                                   "console and the replay page, each with its own token (printed here). "
                                   "The match goes at real time while a live page is open and waits "
                                   "otherwise.")
    add_run_options(p, with_extensions=False)
    add_view_options(p.add_argument_group("web UI"), default_wait=None)
    p.set_defaults(func=main)


def main(args) -> int:
    from ..simulation import Simulation
    from ..web.view import print_urls, start_view

    scene = load_scene(args.scene, overrides_of(args))
    with Simulation(scene, seed=args.seed) as sim, start_view(sim, args.view_host, args.view_port) as view:
        print_urls(view)
        end = args.duration if args.duration is not None else sim.duration
        anchor = None               # (wall, sim time) since the run has been watched without a break
        try:
            while not sim.done and (end is None or sim.time < end - 1e-9):
                if view.server.live_viewers == 0:
                    print("simatch: waiting for a page to open (Ctrl-C to stop)...", file=sys.stderr, flush=True)
                    if not view.wait_for_viewer(args.view_wait):
                        break
                    anchor = (time.perf_counter(), sim.time)
                step = CHUNK if end is None else min(CHUNK, end - sim.time)
                sim.run(seconds=step)
                ahead = (sim.time - anchor[1]) - (time.perf_counter() - anchor[0])   # real time, across chunks
                if ahead > 0:
                    time.sleep(ahead)
            if view.server.live_viewers:
                print("simatch: the match has ended; its pages stay up until they are all closed (Ctrl-C to quit)",
                      file=sys.stderr, flush=True)
            view.finish()
        except KeyboardInterrupt:
            print("simatch: stopped", file=sys.stderr)
        out = sim.result()
    if args.json:
        print(json.dumps(out))
    else:
        print_summary(out)
    return 0
