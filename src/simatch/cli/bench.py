"""``simatch bench``: measure the speeds the README reports (see `simatch.bench`), against their targets.

One benchmark runs in this process. Several run one after another, each in a fresh process of its own
(``simatch bench --only NAME --json``), so that each figure is the one that benchmark gives alone: what an
earlier benchmark left in the interpreter (threads, caches, compiled code) would otherwise slow the next
one down (the distributed lockstep measured a tenth slower after the physics and match benchmarks).
"""

from __future__ import annotations

import importlib
import json
import operator
import subprocess
import sys
from typing import NamedTuple

from ..bench import BENCHMARKS, host
from . import UsageError


class Target(NamedTuple):
    """What a figure must reach: ``measured <op> value`` (``op`` one of ``>=``, ``<=``, ``<``)."""

    op: str
    value: float

    def met(self, measured: float) -> bool:
        return {">=": operator.ge, "<=": operator.le, "<": operator.lt}[self.op](measured, self.value)

    def __str__(self) -> str:
        return f"{self.op} {self.value:g}"


#: The figures simatch is held to, by the key ``simatch bench`` reports them under. This table is the one
#: source of the targets: the README's Performance table states them (tests/test_docs.py holds it to this).
TARGETS: dict[str, Target] = {
    "physics_rtf": Target(">=", 150),
    "match_rtf": Target(">=", 80),
    "record_match_wall_overhead_pct": Target("<=", 15),
    "record_match_mb_per_sim_minute": Target("<=", 10),
    "export_parquet_vs_run": Target("<=", 1),
    "web_fps_min": Target(">=", 30),
    "aerial_encirclement_rtf": Target(">=", 20),
    "distributed_lockstep_rtf": Target(">=", 10),
    "distributed_realtime_latency_p99_ms": Target("<", 5),
    "tournament_speedup_all_cores": Target(">=", 1.8),
    "tournament_ray_overhead_pct": Target("<", 5),
    "envs_msl_5v5_steps_per_cpu_s": Target(">=", 1000),
}


def add_parser(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="measure simulation speeds (real-time factors)",
        description="Runs the benchmarks one after another, each in a fresh process, and prints their figures, "
        "each beside its target where it has one; with --json, one JSON object. Benchmarks: " + ", ".join(BENCHMARKS),
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
            target = TARGETS.get(key)
            if target is None or not isinstance(value, int | float):
                print(f"{key:40s} {value}")
            else:
                print(f"{key:40s} {value}  (target {target}: {'met' if target.met(value) else 'NOT met'})")
    return 0
