#!/usr/bin/env python3
"""Measure the aerial scenes the way a user runs them: ``simatch run SCENE --seed N --json``.

``aerial_encirclement`` (nine ground chasers, three scouting drones, seven targets among obstacles), three
series over the same seeds; each seed also draws another clutter of obstacles (``world.clutter.seed=N``):

* ``scouting``: the scene as shipped;
* ``ground``:   the same team without its drones' eyes (``strategy_params.scouting=false``: they stay landed);
* ``still``:    the chasers stand still (``teams.cyan.strategy=none``).

``pursuit_evasion_3d`` (three pursuing drones, one evading drone among pillars and boxes, under a ceiling):

* ``pincer``: the scene as shipped (the pursuers close in from several sides);
* ``chase``:  every pursuer flies straight at the evader (``teams.cyan.strategy=chase``).

Required: the shipped strategies succeed in at least 9 of 10 seeds (all targets captured within the time
limit; the evader caught within its time limit), and each baseline succeeds in fewer seeds. Prints the
tables (Markdown) and exits with status 1 if a requirement fails.

    python scripts/evaluate_aerial.py                       # both scenes, seeds 0-9
    python scripts/evaluate_aerial.py --scene pursuit_evasion_3d --seeds 5 --json out.json
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

SCENES = {
    "aerial_encirclement": {
        "scouting": [],
        "ground": ["--set", "teams.cyan.strategy_params.scouting=false"],
        "still": ["--set", "teams.cyan.strategy=none"],
    },
    "pursuit_evasion_3d": {
        "pincer": [],
        "chase": ["--set", "teams.cyan.strategy=chase"],
    },
}
SHIPPED = {"aerial_encirclement": "scouting", "pursuit_evasion_3d": "pincer"}


def simatch_command() -> list[str]:
    beside = Path(sys.executable).with_name("simatch")
    return [str(beside)] if beside.exists() else [sys.executable, "-m", "simatch"]


def run_one(scene: str, series: str, seed: int, extra: list[str]) -> dict:
    cmd = simatch_command() + ["run", scene, "--seed", str(seed), "--json", "--quiet"]
    cmd += ["--set", f"world.clutter.seed={seed}"] + SCENES[scene][series] + extra
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    if proc.returncode != 0:
        raise SystemExit(f"failed: {shlex.join(cmd)}\n{proc.stderr}")
    out = json.loads(proc.stdout)
    r = out["result"]
    row = {"scene": scene, "series": series, "seed": seed, "sim_seconds": out["sim_seconds"], "rtf": out["rtf"]}
    if scene == "aerial_encirclement":
        row.update(
            success=r["captured"] == r["targets"],
            detail=f"{r['captured']}/{r['targets']}",
            time_s=r["capture_time_s"],
        )
    else:
        row.update(
            success=r["captured"],
            detail=r.get("captured_by") or "-",
            time_s=r["capture_time_s"],
            collisions=r["collisions"]["total"],
        )
    return row


def table(rows: list[dict]) -> str:
    pursuit = rows and rows[0]["scene"] == "pursuit_evasion_3d"
    head = "| series | seed | result | time [s] | sim s |" + (" collisions |" if pursuit else "")
    lines = [head, "|---" * (5 + pursuit) + "|"]
    for r in rows:
        t = "-" if r["time_s"] is None else f"{r['time_s']:.2f}"
        extra = f" {r['collisions']} |" if pursuit else ""
        lines.append(f"| {r['series']} | {r['seed']} | {r['detail']} | {t} | {r['sim_seconds']:.1f} |{extra}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", choices=sorted(SCENES), action="append", help="only this scene (repeatable)")
    ap.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default 10)")
    ap.add_argument("--only", help="run one series only (e.g. scouting, ground, pincer)")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (default 1)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--json", metavar="FILE", help="also write every run's figures to FILE")
    args = ap.parse_args(argv)
    extra = [a for o in args.overrides for a in ("--set", o)]
    ok = True
    everything = []
    for scene in args.scene or list(SCENES):
        series = [s for s in SCENES[scene] if args.only in (None, s)]
        if not series:
            continue
        jobs = [(s, seed) for s in series for seed in range(args.seeds)]
        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            rows = list(pool.map(lambda job, scene=scene: run_one(scene, job[0], job[1], extra), jobs))
        everything += rows
        print(f"## {scene}\n")
        print(table(rows))
        print()
        wins = {s: sum(r["success"] for r in rows if r["series"] == s) for s in series}
        n = args.seeds
        for s in series:
            times = [r["time_s"] for r in rows if r["series"] == s and r["success"]]
            line = f"{s}: succeeded in {wins[s]} of {n} seeds"
            if times:
                line += f"; time median {statistics.median(times):.1f} s, worst {max(times):.1f} s"
            print(line)
        shipped = SHIPPED[scene]
        if shipped in wins:
            need = -(-9 * n // 10)
            ok &= wins[shipped] >= need
            for s in series:
                if s != shipped:
                    ok &= wins[s] < wins[shipped]
        print()
    rtfs = [r["rtf"] for r in everything if r["rtf"]]
    if rtfs:
        med, lo, hi = statistics.median(rtfs), min(rtfs), max(rtfs)
        print(f"real-time factor (wall clock, whatever else runs): median {med:.0f} (min {lo:.0f}, max {hi:.0f})")
    print("PASS" if ok else "FAIL")
    if args.json:
        Path(args.json).write_text(json.dumps(everything, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
