"""``simatch replay FILE.mcap``: play a recording back on a bus, check that it reproduces, or describe it.

Playback publishes every recorded topic on an in-process bus with the recorded timing (``--speed``
scales it); viewers attach through `EXTENSIONS` (e.g. a live view adds ``--view``). ``--verify``
re-simulates the world from the recorded inputs (``--verify strategies``: the recorded scene, seed,
strategies and operator commands) and compares the model states bit for bit.
``--info`` prints what the recording holds. A truncated or damaged file is read up to what is intact, and
each problem is reported on stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from typing import Any

from ..plugins import load
from . import UsageError
from .run import Progress

#: replay extensions: "module:Class" with add_arguments(parser) and attach(player, args) -> context manager;
#: ``player`` is a `simatch.record.player.Player` (bus, scene, time, duration, pace, done, stop())
EXTENSIONS: list[str] = [
    "simatch.web.view:ReplayViewExtension",
]


def extensions() -> list[Any]:
    return [load(spec, {}, "replay extension")() for spec in EXTENSIONS]


def speed(text: str) -> float | None:
    if text.strip().lower() in ("max", "inf", "0"):
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number or 'max', got {text!r}")
    return value


def add_parser(sub) -> None:
    p = sub.add_parser(
        "replay",
        help="play a recording back on the bus, or check that it reproduces",
        description="Publishes every topic of a recording (simatch run --record) on the bus with "
        "its recorded timing, so that any node or viewer sees the game again. "
        "--verify re-simulates the world from the recorded inputs (every robot command as the simulator "
        "applied it, placements, operator actions) and checks that the model states match the recording "
        "bit for bit; --verify strategies runs the recorded strategies, judge and coaches again instead.",
    )
    p.add_argument("file", nargs="?", metavar="FILE.mcap", help="a recording")
    p.add_argument(
        "--speed",
        type=speed,
        default=1.0,
        metavar="X",
        help="simulated seconds per wall second (default 1: real time; 'max': as fast as possible)",
    )
    p.add_argument(
        "--from",
        dest="start",
        type=float,
        default=0.0,
        metavar="T",
        help="start at simulated time T seconds (the latest message of every topic before T is published first)",
    )
    p.add_argument(
        "--verify",
        nargs="?",
        const="auto",
        metavar="inputs|strategies",
        help="re-simulate the run and compare the model states bit for bit (exit status 1 if they differ): "
        "from the recorded world inputs (the default; any run), or from the recorded strategies, judge and "
        "coaches ('strategies': embedded and undisturbed lockstep runs only)",
    )
    p.add_argument("--info", action="store_true", help="describe the recording and exit")
    p.add_argument("--json", action="store_true", help="with --verify or --info: print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    for ext in extensions():
        ext.add_arguments(p)
    p.set_defaults(func=main)


def _warn(problems: list[str], already: int = 0) -> int:
    for text in problems[already:]:
        print(f"simatch: warning: {text}", file=sys.stderr)
    return len(problems)


def main(args) -> int:
    from ..record.reader import Recording, RecordingError
    from ..record.reproduce import MODES, VerifyError, verify

    if args.verify is not None and args.verify not in MODES and args.file is None:
        args.file, args.verify = args.verify, "auto"  # `replay --verify FILE`
    if args.file is None:
        raise UsageError("which recording? simatch replay FILE.mcap [--verify | --info | --speed X]")
    if args.verify is not None and args.verify not in MODES:
        raise UsageError(f"--verify {args.verify}: expected one of {', '.join(m for m in MODES if m != 'auto')}")
    if args.start < 0:
        raise UsageError("--from must be a time >= 0")
    try:
        rec = Recording(args.file)
    except RecordingError as exc:
        raise UsageError(str(exc)) from None
    if args.info:
        return _info(rec, args)
    if args.verify is not None:
        shown = _warn(rec.problems)
        progress = Progress(rec.duration, not args.quiet and not args.json)
        try:
            verdict = verify(rec.path, progress=progress, mode=args.verify)
        except (VerifyError, RecordingError) as exc:
            raise UsageError(str(exc)) from None
        finally:
            progress.close()
        _warn(verdict.problems, shown)
        if args.json:
            print(json.dumps(verdict.as_dict()))
        else:
            print(verdict.describe())
        return 0 if verdict.identical else 1
    return _play(rec, args)


def _play(rec, args) -> int:
    import time

    from ..record.player import Player

    shown = _warn(rec.problems)
    player = Player(rec, pace=args.speed, start=args.start)
    if args.start > player.duration:
        raise UsageError(f"--from {args.start}: the recording ends at {player.duration:.3f} s")
    progress = Progress(max(0.0, player.duration - args.start), not args.quiet)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        for ext in extensions():
            stack.enter_context(ext.attach(player, args))
        try:
            player.play(progress=lambda t: progress(t - args.start))
        finally:
            progress.close()
    wall = time.perf_counter() - t0
    _warn(rec.problems, shown)
    print(
        f"replayed {player.published} messages on {len(player.topics)} topics, "
        f"t={args.start:.3f}..{player.time:.3f} s, in {wall:.2f} s wall"
    )
    return 0


def _recorded(text: str | None, default=None, number: bool = False):
    """A metadata value as recorded (JSON, or a number), or ``default`` if the file's copy is damaged."""
    try:
        return default if text is None else (int(text) if number else json.loads(text))
    except ValueError:
        return default


def _info(rec, args) -> int:
    from ..record.reader import RecordingError

    meta = rec.metadata
    counts = rec.message_counts()  # the summary's: every channel, the 3D scene's too
    if counts is None:
        counts = _recorded((rec.end or {}).get("messages"))  # the simatch_end record's: bus topics only
        counts = counts if isinstance(counts, dict) else None
    try:
        overrides = rec.overrides()
    except RecordingError as exc:
        rec.problems.append(str(exc))
        overrides = None
    info = {
        "file": str(rec.path),
        "simatch": rec.is_simatch,
        "finalised": rec.finalised,
        "status": (rec.end or {}).get("status", "not finalised"),
        "scene": meta.get("scene_name"),
        "seed": _recorded(meta.get("seed"), number=True),
        "overrides": overrides,
        "simatch_version": meta.get("simatch_version"),
        "command_line": _recorded(meta.get("command_line")),
        "start": rec.start_ns / 1e9,
        "end": rec.end_ns / 1e9,
        "chunks": len(rec.chunks),
        "state_digest": (rec.end or {}).get("state_digest"),
        "topics": rec.topics(),
        "messages": counts,
        "problems": rec.problems,
    }
    if args.json:
        print(json.dumps(info))
        return 0
    print(
        f"{info['file']}: {'simatch recording' if rec.is_simatch else 'MCAP file (no simatch metadata)'}, "
        f"{info['status']}"
    )
    if rec.is_simatch:
        print(
            f"scene {info['scene']}  seed {info['seed']}  overrides {json.dumps(info['overrides'])}  "
            f"simatch {info['simatch_version']}"
        )
        line = info["command_line"]
        print(f"command line: {' '.join(map(str, line)) if isinstance(line, list) else line or ''}")
    print(f"simulated time {info['start']:.3f} .. {info['end']:.3f} s in {info['chunks']} chunks")
    if info["state_digest"]:
        print(f"final state digest {info['state_digest']}")
    print(f"topics: {len(info['topics'])}")
    for topic, typ in sorted(info["topics"].items()):
        n = f"{counts.get(topic, '')}" if counts else ""
        print(f"  {topic:32s} {typ:40s} {n}")
    _warn(rec.problems)
    return 0
