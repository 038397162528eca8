#!/usr/bin/env python3
"""Match quality of the default team, measured by whole refereed matches (issue 5, item 4).

Runs ``simatch run msl_5v5 --json`` for each match (one process per match, several at once with --jobs),
with the automatic referee judging, and prints a table per match and a summary against the targets:

* nubot against simple: at least 18 wins in 20 matches and at least 3 goals a match on average;
* nubot against nubot: a goal in most matches, at most 3 fouls per team per match, and no freeze: the
  match reaches its end, play restarts (no restart taken again and again) and a ball stuck between
  robots stays rare (the referee's "no progress" dropped balls are counted).

The nubot team plays cyan in half the matches and magenta in the other half. A match lasts two halves of
``--half`` seconds (default 300: a ten-minute match). Example:

    python scripts/evaluate_matches.py --pairing simple --matches 20 --jobs 2 --out simple.json
    python scripts/evaluate_matches.py --pairing nubot --matches 10
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

from simatch.scene.referee.log import FOUL_TYPES

RETAKES_FOR_A_LOOP = 3
FOUL_LOOP = 5  # the same robot fouled for the same rule this many times in a row is stuck
FOUL_LOOP_GAP = 15.0  # ... each within this many seconds of the one before
#: event types left out of the --out file (the rest, every foul, goal, ball out and restart, is kept)
QUIET = frozenset({"stage"})  # the same restart taken again this many times in a row is a stuck loop


def match_command(simatch: list[str], cyan: str, magenta: str, seed: int, half: float) -> list[str]:
    return simatch + [
        "run",
        "msl_5v5",
        "--json",
        "--quiet",
        "--seed",
        str(seed),
        "--set",
        f"teams.cyan.strategy={cyan}",
        "--set",
        f"teams.magenta.strategy={magenta}",
        "--set",
        "match.halves=2",
        "--set",
        f"match.half_duration={half}",
    ]


def play(simatch: list[str], cyan: str, magenta: str, seed: int, half: float) -> dict:
    cmd = match_command(simatch, cyan, magenta, seed, half)
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{shlex.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    out = json.loads(proc.stdout)
    out["_wall"] = time.monotonic() - t0
    out["_teams"] = {"cyan": cyan, "magenta": magenta}
    return out


def longest_foul_repeat(events: list[dict], gap: float = FOUL_LOOP_GAP) -> int:
    """The longest run of the same robot committing the same foul again and again, each within ``gap``
    seconds of the one before (a robot stuck where it may not be, fouled at every restart)."""
    best = run = 0
    last, last_t = None, -math.inf
    for ev in events:
        if ev["type"] not in FOUL_TYPES:
            continue
        key = (ev["type"], ev.get("team"), ev.get("robot"))
        run = run + 1 if key == last and ev["t"] - last_t <= gap else 1
        last, last_t = key, ev["t"]
        best = max(best, run)
    return best


def longest_retake_run(events: list[dict]) -> int:
    """The longest run of the same restart retaken (set-piece fouls by the defending side)."""
    best = run = 0
    last = None
    for ev in events:
        if ev["type"] in ("set_piece_distance", "kickoff_half", "dropped_ball_distance") and "taken again" in ev.get(
            "detail", ""
        ):
            key = ev.get("detail", "").split(":")[-1]
            run = run + 1 if key == last else 1
            last = key
            best = max(best, run)
        elif ev["type"] in ("ball_in_play", "goal"):
            run, last = 0, None
    return best


def summarise(out: dict, nubot_team: str, duration: float) -> dict:
    r = out["result"]
    other = "magenta" if nubot_team == "cyan" else "cyan"
    events = out["events"]
    return {
        "seed": out["seed"],
        "nubot_colour": nubot_team,
        "goals_for": r["score"][nubot_team],
        "goals_against": r["score"][other],
        "fouls_nubot": r["fouls"][nubot_team],
        "fouls_other": r["fouls"][other],
        "fouls_by_type": _fouls_by_type(events),
        "no_progress": sum(1 for e in events if e["type"] == "no_progress"),
        "retake_loop": longest_retake_run(events),
        "foul_loop": longest_foul_repeat(events),
        "ended": bool(r.get("ended")) and out["sim_seconds"] >= duration - 1e-6,
        "rtf": out["rtf"],
        "wall_s": round(out["_wall"], 1),
    }


def _fouls_by_type(events: list[dict]) -> dict:
    """Fouls per team and rule, counted as the referee counts them (its FOUL_TYPES: a restart not taken in
    time, a card or a goal is an event, not a foul)."""
    counts: dict[str, int] = {}
    for e in events:
        if e.get("team") and e["type"] in FOUL_TYPES:
            key = f"{e['team']}:{e['type']}"
            counts[key] = counts.get(key, 0) + 1
    return counts


def check_fouls(row: dict) -> None:
    """The table's fouls per type must add up to the referee's own count per team."""
    for colour, total in (
        (row["nubot_colour"], row["fouls_nubot"]),
        ("magenta" if row["nubot_colour"] == "cyan" else "cyan", row["fouls_other"]),
    ):
        mine = sum(n for k, n in row["fouls_by_type"].items() if k.startswith(colour + ":"))
        if mine != total:
            raise RuntimeError(f"seed {row['seed']}: {mine} fouls of {colour} by type, the referee counted {total}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--pairing",
        choices=["simple", "nubot", "both"],
        default="both",
        help="nubot against simple, against itself, or both (default)",
    )
    ap.add_argument(
        "--matches", type=int, default=None, help="matches per pairing (default: 20 against simple, 10 against nubot)"
    )
    ap.add_argument("--half", type=float, default=300.0, help="length of each of the two halves [s]")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=1, help="matches run at once (one process each)")
    ap.add_argument("--simatch", default=None, help="the simatch command (default: this Python with -m simatch)")
    ap.add_argument("--out", default=None, help="write every match's summary and result here (JSON)")
    args = ap.parse_args(argv)
    simatch = shlex.split(args.simatch) if args.simatch else [sys.executable, "-m", "simatch"]
    pairings = ["simple", "nubot"] if args.pairing == "both" else [args.pairing]
    report: dict = {}
    status = 0
    for pairing in pairings:
        n = args.matches or (20 if pairing == "simple" else 10)
        jobs = []
        for k in range(n):
            seed = args.first_seed + k
            nubot_team = "cyan" if k % 2 == 0 else "magenta"
            cyan = "nubot" if nubot_team == "cyan" else pairing
            magenta = pairing if nubot_team == "cyan" else "nubot"
            jobs.append((seed, nubot_team, cyan, magenta))
        print(f"\n## nubot against {pairing}: {n} matches of 2 x {args.half:g} s ({args.jobs} at once)", flush=True)
        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            outs = list(pool.map(lambda j: play(simatch, j[2], j[3], j[0], args.half), jobs))
        rows = [summarise(out, j[1], 2 * args.half) for out, j in zip(outs, jobs)]
        for row in rows:
            check_fouls(row)
        print_table(rows)
        verdict = judge(pairing, rows)
        for line in verdict["lines"]:
            print(line)
        status |= 0 if verdict["ok"] else 1
        report[pairing] = {
            "matches": rows,
            "verdict": verdict,
            "results": [o["result"] for o in outs],
            "events": [[e for e in o["events"] if e["type"] not in QUIET] for o in outs],
        }
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            json.dump(report, f, indent=1)
    return status


def print_table(rows: list[dict]) -> None:
    print(
        "\n| seed | nubot plays | score (nubot-other) | fouls nubot | fouls other | no progress | retake loop "
        "| foul loop | ended | rtf |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['seed']} | {r['nubot_colour']} | {r['goals_for']}-{r['goals_against']} | {r['fouls_nubot']} | "
            f"{r['fouls_other']} | {r['no_progress']} | {r['retake_loop']} | {r['foul_loop']} | "
            f"{'yes' if r['ended'] else 'NO'} | "
            f"{r['rtf']} |"
        )


def judge(pairing: str, rows: list[dict]) -> dict:
    n = len(rows)
    goals = sum(r["goals_for"] for r in rows)
    wins = sum(r["goals_for"] > r["goals_against"] for r in rows)
    fouls = [r["fouls_nubot"] for r in rows]
    lines = []
    if pairing == "simple":
        need_wins = round(18 * n / 20)
        ok = wins >= need_wins and goals / n >= 3.0
        lines.append(
            f"\nwins {wins}/{n} (target >= {need_wins}), goals per match {goals / n:.2f} (target >= 3), "
            f"nubot fouls per match {sum(fouls) / n:.2f}: {'PASS' if ok else 'FAIL'}"
        )
    else:
        scored = sum(r["goals_for"] + r["goals_against"] > 0 for r in rows)
        fouls_both = fouls + [r["fouls_other"] for r in rows]
        worst = max(fouls_both) if fouls_both else 0
        frozen = [
            r["seed"]
            for r in rows
            if not r["ended"] or r["retake_loop"] >= RETAKES_FOR_A_LOOP or r["foul_loop"] >= FOUL_LOOP
        ]
        ok = scored > n / 2 and worst <= 3 and not frozen
        lines.append(
            f"\nmatches with a goal {scored}/{n} (target: most), goals per match "
            f"{sum(r['goals_for'] + r['goals_against'] for r in rows) / n:.2f}, fouls per team per match: "
            f"mean {sum(fouls_both) / len(fouls_both):.2f}, max {worst} (target <= 3), no-progress "
            f"dropped balls per match {sum(r['no_progress'] for r in rows) / n:.2f}, frozen matches "
            f"{frozen or 'none'}: {'PASS' if ok else 'FAIL'}"
        )
    return {"ok": ok, "lines": lines, "wins": wins, "goals_per_match": goals / n}


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
