"""``simatch bench``: measure the speeds the README reports (see `simatch.bench`).

One benchmark runs in this process. Several run one after another, each in a fresh process of its own
(``simatch bench --only NAME --json``), so that each figure is the one that benchmark gives alone: after
the physics and match benchmarks in one interpreter, with nothing of theirs left running, the distributed
lockstep measured 9.7-10.6x against 11.5x alone, and its embedded run 28-30x against 31.5-32x (2026-11-21).
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

from ..bench import BENCHMARKS, host
from . import UsageError


def add_parser(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="measure simulation speeds (real-time factors)",
        description="Runs the benchmarks one after another, each in a fresh process, and prints "
        "their figures; with --json, one JSON object. Benchmarks: " + ", ".join(BENCHMARKS),
    )
    p.add_argument("--json", action="store_true", help="print exactly one JSON object")
    p.add_argument("--only", action="append", default=[], metavar="NAME", help="run only this benchmark (repeatable)")
    p.add_argument(
        "--seconds", type=float, metavar="S", help="simulated seconds per benchmark (default: each one's own)"
    )
    p.set_defaults(func=main)


def run_here(name: str, seconds: float | None) -> dict:
    """``name`` in this process; its figures and the CPU time the host stole meanwhile (`bench.host`)."""
    module, _, func = BENCHMARKS[name].partition(":")
    before = host.cpu_times()
    out = getattr(importlib.import_module(module), func)(seconds)
    out[f"{name}_host_steal_pct"] = host.steal_pct(before, host.cpu_times())
    return out


def run_alone(name: str, seconds: float | None) -> dict:
    """``name`` in a fresh process; its figures (UsageError, with what it said, if it fails)."""
    cmd = [sys.executable, "-m", "simatch", "bench", "--only", name, "--json"]
    if seconds is not None:
        cmd += ["--seconds", repr(seconds)]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        tail = "\n".join(out.stderr.strip().splitlines()[-15:])
        raise UsageError(f"benchmark {name} failed (exit {out.returncode}):\n{tail}")
    try:
        return json.loads(out.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        raise UsageError(f"benchmark {name} printed no JSON object: {out.stdout[-300:]!r}") from None


def ratios(out: dict) -> dict:
    """Figures that compare two benchmarks of the same ``simatch bench`` run: ``match_physics_ratio``, the
    whole match's speed as a fraction of the physics alone (``match_rtf / physics_rtf``; 0.5 means the
    strategies, perception, bus and referee together cost as much as the physics), and the same of the
    CPU-time figures (``match_physics_cpu_ratio``, steadier on a machine shared with other work)."""
    found = {}
    for key, match_key, physics_key in (
        ("match_physics_ratio", "match_rtf", "physics_rtf"),
        ("match_physics_cpu_ratio", "match_cpu_rtf", "physics_cpu_rtf"),
    ):
        match, physics = out.get(match_key), out.get(physics_key)
        if isinstance(match, int | float) and isinstance(physics, int | float) and physics > 0:
            found[key] = round(match / physics, 3)
    return found


def main(args) -> int:
    names = args.only or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        raise UsageError(f"unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(BENCHMARKS)}")
    if args.seconds is not None and not args.seconds > 0:
        raise UsageError("--seconds must be positive")
    run = run_here if len(names) == 1 else run_alone
    out: dict = {}
    for k, name in enumerate(names, 1):
        if not args.json:
            print(f"[{k}/{len(names)}] running {name} ...", file=sys.stderr, flush=True)
        out.update(run(name, args.seconds))
    out.update(ratios(out))
    if args.json:
        print(json.dumps(out))
    else:
        for key, value in out.items():
            print(f"{key:40s} {value}")
    return 0
