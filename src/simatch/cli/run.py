"""``simatch run SCENE``: run a scene embedded in this process (no server to start).

Options shared with ``simatch server`` are added by `add_run_options`. Features that attach to a run
(recording, the live view) are extensions listed in `EXTENSIONS`: each adds its options and wraps the run.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import signal
import sys
from collections.abc import Callable
from typing import Any

from ..config.loader import load_scene, parse_override
from . import UsageError

#: run extensions: "module:Class" with add_arguments(parser) and attach(sim, args) -> context manager
EXTENSIONS: list[str] = [
    "simatch.ros1.embedded:Ros1Extension",  # first: the teams it hands to ROS are 'external' in a recording
    "simatch.record.extension:RecordExtension",
    "simatch.web.view:ViewExtension",
    "simatch.report.extension:ReportExtension",
    "simatch.ros2.extension:Ros2Extension",
]


SCENE_HELP = "a shipped scene name (see 'simatch scenes') or a path to a .toml scene file"


def add_run_options(
    p, with_extensions: bool = True, scene_help: str = SCENE_HELP, scene_metavar: str = "SCENE"
) -> None:
    p.add_argument("scene", metavar=scene_metavar, help=scene_help)
    p.add_argument(
        "--duration", type=float, metavar="S", help="simulated seconds to run (default: until the judge ends the run)"
    )
    p.add_argument("--seed", type=int, default=0, metavar="N", help="random seed (default 0)")
    add_overrides_option(p, "override a scene value (dotted path into the TOML), e.g. teams.magenta.strategy=simple")
    p.add_argument("--realtime", action="store_true", help="pace the simulation at wall-clock speed")
    p.add_argument("--json", action="store_true", help="print exactly one JSON object with the run's results")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--events",
        type=_event_count,
        default=30,
        metavar="N|all",
        help="how many of the run's last events the summary prints (default 30; 'all': the whole "
        "event log; --json always carries every event)",
    )
    for ext in extensions() if with_extensions else ():
        ext.add_arguments(p)


def add_overrides_option(p, help: str) -> None:
    """``--set KEY=VALUE`` (repeatable) into ``args.overrides``; `overrides_of` reads them."""
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=help)


def _event_count(text: str) -> int | None:
    if text == "all":
        return None
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of events or 'all', got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"expected a number of events >= 0 or 'all', got {n}")
    return n


def extensions() -> list[Any]:
    out = []
    for spec in EXTENSIONS:
        module, _, attr = spec.partition(":")
        out.append(getattr(importlib.import_module(module), attr)())
    return out


def add_parser(sub) -> None:
    p = sub.add_parser(
        "run",
        help="run a scene embedded in this process",
        description="Run a scene (world, teams, judge) in this process, in lockstep: the same "
        "scene and seed give the same run bit for bit. With --json, prints one "
        "JSON object: scene, seed, sim_seconds, wall_seconds, rtf, state_digest, "
        "result (judge-specific) and events.",
    )
    add_run_options(p)
    p.set_defaults(func=main)


def overrides_of(args) -> dict:
    return dict(parse_override(o) for o in args.overrides)


def run_duration(sim, args) -> float:
    if args.duration is not None:
        if args.duration <= 0:
            raise UsageError("--duration must be positive")
        return args.duration
    if sim.duration is None:
        raise UsageError(
            f"scene {sim.scene.name} has no natural end (its judge is '{sim.scene.spec.judge.kind}'); "
            f"give --duration SECONDS"
        )
    return sim.duration


class Progress:
    """A progress bar on a terminal (stderr), nothing otherwise. ``status()``, if given, is a short text
    shown beside the bar (a match's score and stage)."""

    def __init__(self, total: float, enabled: bool, status: Callable[[], str] | None = None):
        self.bar = None
        self.status = status
        if enabled and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(
                total=round(total, 3),
                unit="sim s",
                file=sys.stderr,
                dynamic_ncols=True,
                bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]{postfix}",
            )
        self.last = 0.0
        self._shown = ""

    def __call__(self, t: float) -> None:
        if self.bar is not None:
            if self.status is not None:
                text = self.status()
                if text != self._shown:
                    self._shown = text
                    self.bar.set_postfix_str(text, refresh=False)
            self.bar.update(t - self.last)
            self.last = t

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def match_status(sim) -> Callable[[], str] | None:
    """The score and stage of a run whose judge keeps a game (the referee), for the progress bar."""
    if sim.game is None:
        return None

    def status() -> str:
        game = sim.game
        score = " ".join(f"{team} {goals}" for team, goals in game["score"].items())
        return f"{score}, {game['stage'].replace('_', ' ')}"

    return status


def _readable(value: Any) -> Any:
    """Floats rounded to 6 significant digits, for people (the JSON output keeps every digit)."""
    if isinstance(value, float):
        return float(f"{value:.6g}")
    if isinstance(value, dict):
        return {k: _readable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_readable(v) for v in value]
    return value


def print_result(out: dict, as_json: bool, events: int | None = 30) -> None:
    """A run's result (`Simulation.result`) on stdout: exactly one JSON object (``--json``), or `print_summary`
    with the last ``events`` events."""
    if as_json:
        print(json.dumps(out))
    else:
        print_summary(out, limit=events)


def print_summary(out: dict, file=sys.stdout, limit: int | None = 30) -> None:
    """The run for people: the last ``limit`` events (None: all), then what ran, how fast and the result — last,
    so that the final screen of a terminal shows the result however long the event log is."""
    events = out["events"]
    shown = events if limit is None else events[max(0, len(events) - limit) :]
    print(f"events: {len(events)}", file=file)
    if len(shown) < len(events):
        print(
            f"  ... ({len(events) - len(shown)} earlier events: --events all prints every one, "
            f"--json gives them as data)",
            file=file,
        )
    for ev in shown:
        rest = {k: v for k, v in ev.items() if k not in ("t", "type")}
        print(f"  {ev['t']:9.3f}  {ev['type']:22s} {json.dumps(_readable(rest)) if rest else ''}", file=file)
    print(f"scene {out['scene']}  seed {out['seed']}", file=file)
    rtf = f"{out['rtf']:.1f}" if out["rtf"] else "-"
    print(
        f"simulated {out['sim_seconds']:.2f} s in {out['wall_seconds']:.2f} s wall (real-time factor {rtf})", file=file
    )
    print(f"state digest {out['state_digest']}", file=file)
    print("result:", file=file)
    for key, value in out["result"].items():
        print(f"  {key}: {json.dumps(_readable(value))}", file=file)


def main(args) -> int:
    from ..simulation import Simulation

    scene = load_scene(args.scene, overrides_of(args))
    with Simulation(scene, seed=args.seed) as sim, contextlib.ExitStack() as stack:
        for ext in extensions():
            stack.enter_context(ext.attach(sim, args))
        duration = run_duration(sim, args)
        progress = Progress(duration, not args.quiet, match_status(sim))
        try:
            with sim.stopping_on(signal.SIGINT, KeyboardInterrupt):
                sim.run(seconds=duration, progress=progress, realtime=args.realtime)
        finally:
            progress.close()
        out = sim.result()
    print_result(out, args.json, args.events)
    return 0
