"""``simatch serve SCENE | FILE.mcap``: a standing match server for the web UI, or a recording shown in it.

Unlike ``simatch run --view`` (a run that is also shown), the scene here exists to be watched and
commanded from the pages: it advances at real time while at least one coach page or the referee
console is open and waits while none is, until the judge ends it, ``--duration`` is reached or Ctrl-C.
Then the pages stay up (the replay page goes through the whole match) until they are all closed.

Given a recording (``simatch run ... --record FILE.mcap``), it does what ``simatch replay FILE.mcap
--view`` does: the recording plays on the bus (``--speed``, ``--from``) for the live pages, and the replay
page goes through all of it.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from ..config.loader import load_scene
from . import UsageError
from .run import add_run_options, overrides_of, print_result

CHUNK = 0.05  # [s] simulated between two looks at the open pages
MCAP_MAGIC = b"\x89MCAP"


def add_parser(sub) -> None:
    from ..web.view import add_view_options
    from .replay import speed

    p = sub.add_parser(
        "serve",
        help="serve a scene (or a recording) to the web UI: coach pages, referee console, replay",
        description="Run a scene for the web UI: the coach page of each team, the referee "
        "console and the replay page, each with its own token (printed here). "
        "The match goes at real time while a live page is open and waits "
        "otherwise. Given a recording (FILE.mcap), show it: it plays on the bus for "
        "the live pages and the replay page goes through all of it.",
    )
    add_run_options(
        p,
        with_extensions=False,
        scene_metavar="SCENE|FILE.mcap",
        scene_help="a shipped scene name (see 'simatch scenes'), a path to a .toml scene file, or a recording "
        "(FILE.mcap, made by 'simatch run SCENE --record FILE.mcap') to show",
    )
    add_view_options(p.add_argument_group("web UI"), default_wait=None)
    rec = p.add_argument_group("a recording (SCENE is a FILE.mcap)")
    rec.add_argument(
        "--speed",
        type=speed,
        default=None,
        metavar="X",
        help="simulated seconds per wall second (default 1: real time; 'max': as fast as possible)",
    )
    rec.add_argument(
        "--from", dest="start", type=float, default=None, metavar="T", help="start playing at simulated time T seconds"
    )
    p.set_defaults(func=main)


def is_recording(name: str) -> bool:
    """``name`` is a recording file (an MCAP file, or a name that says so), not a scene."""
    path = Path(name)
    if path.suffix.lower() == ".mcap":
        return True
    try:
        with open(path, "rb") as f:
            return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except OSError:
        return False


def main(args) -> int:
    if is_recording(args.scene):
        return serve_recording(args)
    for option, value in (("--speed", args.speed), ("--from", args.start)):
        if value is not None:
            raise UsageError(f"{option} is for a recording (simatch serve FILE.mcap), not a scene")
    return serve_scene(args)


def serve_scene(args) -> int:
    from ..simulation import Simulation
    from ..web.view import announce, start_view

    scene = load_scene(args.scene, overrides_of(args))
    with Simulation(scene, seed=args.seed) as sim, start_view(sim, args.view_host, args.view_port) as view:
        announce(view, args)
        end = args.duration if args.duration is not None else sim.duration
        anchor = None  # (wall, sim time) since the run has been watched without a break
        try:
            while not sim.done and (end is None or sim.time < end - 1e-9):
                if view.server.live_viewers == 0:
                    print("simatch: waiting for a page to open (Ctrl-C to stop)...", file=sys.stderr, flush=True)
                    if not view.wait_for_viewer(args.view_wait):
                        break
                    anchor = (time.perf_counter(), sim.time)
                step = CHUNK if end is None else min(CHUNK, end - sim.time)
                sim.run(seconds=step)
                ahead = (sim.time - anchor[1]) - (time.perf_counter() - anchor[0])  # real time, across chunks
                if ahead > 0:
                    time.sleep(ahead)
            if view.server.clients:
                print(
                    "simatch: the match has ended; its pages stay up until they are all closed (Ctrl-C to quit)",
                    file=sys.stderr,
                    flush=True,
                )
            view.finish()
        except KeyboardInterrupt:
            print("simatch: stopped", file=sys.stderr)
        out = sim.result()
    print_result(out, args.json, args.events)
    return 0


def serve_recording(args) -> int:
    """What ``simatch replay FILE --view`` does, with serve's options."""
    from ..record.player import Player
    from ..record.reader import Recording, RecordingError
    from ..web.view import announce, linger, start_recording_view, wait_for_page

    given = [
        name
        for name, value in (
            ("--set", args.overrides),
            ("--seed", args.seed),
            ("--duration", args.duration),
            ("--realtime", args.realtime),
        )
        if value
    ]
    if given:
        raise UsageError(f"{', '.join(given)}: a recording is shown as it was recorded (use --speed and --from)")
    start = args.start or 0.0
    if start < 0:
        raise UsageError("--from must be a time >= 0")
    try:
        rec = Recording(args.scene)
    except RecordingError as exc:
        raise UsageError(str(exc)) from None
    for problem in rec.problems:
        print(f"simatch: warning: {problem}", file=sys.stderr)
    player = Player(rec, pace=1.0 if args.speed is None else args.speed, start=start)
    if start > player.duration:
        raise UsageError(f"--from {start}: the recording ends at {player.duration:.3f} s")
    with start_recording_view(player, args.view_host, args.view_port) as view:
        announce(view, args, first="replay")
        try:
            wait_for_page(view, args.view_wait, any_page=True)
            player.play()
            linger(view, "the playback")
        except KeyboardInterrupt:
            print("simatch: stopped", file=sys.stderr)
    summary = {"file": str(rec.path), "published": player.published, "from": start, "until": round(player.time, 6)}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"replayed {player.published} messages, t={start:.3f}..{player.time:.3f} s")
    return 0
