#!/usr/bin/env python3
"""Measure the encirclement scene the way a user runs it: ``simatch run encirclement_9v7 --seed N --json``.

Two series over the same seeds:

* ``herding``: the scene as shipped (the chasers' strategy ``encircle``);
* ``still``:   the chasers stand still (``--set teams.cyan.strategy=none``).

Required (issue 5, item 5): all seven targets captured within 300 s of simulated time in at least 9 of
10 seeds while herding, and no target captured in any seed while the chasers stand still. Prints one
table (Markdown) and exits with status 1 if a requirement fails.

    python scripts/evaluate_encirclement.py                 # seeds 0-9, both series
    python scripts/evaluate_encirclement.py --seeds 20 --json results.json
"""

from __future__ import annotations

import argparse
import json
import shlex
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

SCENE = "encirclement_9v7"
SERIES = {"herding": [], "still": ["--set", "teams.cyan.strategy=none"]}
LIMIT_S = 300.0


def simatch_command() -> list[str]:
    """The ``simatch`` command of this interpreter's environment (a checkout's .venv or an install)."""
    beside = Path(sys.executable).with_name("simatch")
    return [str(beside)] if beside.exists() else [sys.executable, "-m", "simatch"]


def run_one(series: str, seed: int, extra: list[str]) -> dict:
    cmd = simatch_command() + ["run", SCENE, "--seed", str(seed), "--json", "--quiet"] + SERIES[series] + extra
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    if proc.returncode != 0:
        raise SystemExit(f"failed: {shlex.join(cmd)}\n{proc.stderr}")
    out = json.loads(proc.stdout)
    r = out["result"]
    return {
        "series": series,
        "seed": seed,
        "targets": r["targets"],
        "captured": r["captured"],
        "capture_time_s": r["capture_time_s"],
        "sim_seconds": out["sim_seconds"],
        "wall_seconds": out["wall_seconds"],
        "rtf": out["rtf"],
        "top_speed_m_s": r.get("top_speed_m_s", {}),
        "chasers": r.get("chasers", "cyan"),
        "target_team": r.get("target_team", "magenta"),
        "state_digest": out["state_digest"],
    }


def all_in_time(row: dict) -> bool:
    return row["captured"] == row["targets"] and row["capture_time_s"] is not None and row["capture_time_s"] <= LIMIT_S


def table(rows: list[dict]) -> str:
    lines = [
        "| series | seed | captured | last capture [s] | top speed targets / chasers [m/s] | sim s | rtf |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        speeds = row["top_speed_m_s"]
        top = f"{speeds.get(row['target_team'], 0.0):.2f} / {speeds.get(row['chasers'], 0.0):.2f}"
        t = row["capture_time_s"]
        lines.append(
            f"| {row['series']} | {row['seed']} | {row['captured']}/{row['targets']} | "
            f"{'-' if t is None else f'{t:.2f}'} | {top} | {row['sim_seconds']:.1f} | {row['rtf']:.0f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default 10)")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (default 1: the rtf column stays honest)")
    ap.add_argument("--only", choices=sorted(SERIES), help="run one series only")
    ap.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="an extra scene override for every run (e.g. perception.position_noise=0.05)",
    )
    ap.add_argument("--json", metavar="FILE", help="also write every run's figures to FILE")
    args = ap.parse_args(argv)
    extra = [a for o in args.overrides for a in ("--set", o)]
    series = [args.only] if args.only else list(SERIES)
    jobs = [(s, seed) for s in series for seed in range(args.seeds)]
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(lambda job: run_one(job[0], job[1], extra), jobs))
    print(table(rows))
    print()
    ok = True
    herding = [r for r in rows if r["series"] == "herding"]
    if herding:
        wins = [r for r in herding if all_in_time(r)]
        need = -(-9 * len(herding) // 10)  # 9 of 10, rounded up
        times = [r["capture_time_s"] for r in wins]
        summary = (
            f"herding: all targets captured within {LIMIT_S:g} s in {len(wins)} of {len(herding)} seeds "
            f"(required: {need})"
        )
        if times:
            summary += f"; last capture median {statistics.median(times):.1f} s, worst {max(times):.1f} s"
        print(summary)
        ok &= len(wins) >= need
    still = [r for r in rows if r["series"] == "still"]
    if still:
        caught = sum(r["captured"] for r in still)
        print(f"still: {caught} targets captured over {len(still)} seeds with the chasers standing still (required: 0)")
        ok &= caught == 0
    rtfs = [r["rtf"] for r in rows if r["rtf"]]
    if rtfs:
        print(f"real-time factor: median {statistics.median(rtfs):.0f} (min {min(rtfs):.0f}, max {max(rtfs):.0f})")
    print("PASS" if ok else "FAIL")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"scene": SCENE, "rows": rows, "pass": ok}, f, indent=2)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
