#!/usr/bin/env python3
"""The referee in numbers (issue 24, item 6): every call of the automatic referee over seeded whole matches.

Plays ``--matches`` seeded matches of each pairing — nubot against nubot, and nubot against simple (nubot
plays cyan in half of those, magenta in the other half) — each two halves of ``--half`` seconds (900: the
MSL match of ``make run``), with the automatic referee judging, and lists every call it made by rule: the
fouls, goals and disallowed goals, balls out, restarts not taken in time, dropped balls for no progress,
cards and send-offs. For every rule it writes a sample of the situations it was called in (spread over the
matches) as scenes a person can run again and look at in the web UI::

    simatch run audit/scenarios/charging_1.toml --view

Each such scene places every robot and the ball where they stood when the call was made, the teams playing
on from there with the referee judging (in play, or in the restart that was being taken), and its header
says what was called — the time, the measured value against its limit, the referee's reason — and the
command that plays the original match up to that moment. ``audit/audit.json`` keeps every call with its
situation, and the counts per rule and match (``--markdown`` prints them as the table of docs/referee.md).

Matches are long (a whole match is about a minute of wall time on a quiet two-core machine): the script
lowers its own priority (``--nice``), shows a progress bar in a terminal, and runs one match at a time unless
``--jobs`` says otherwise. Examples::

    python scripts/referee_audit.py --matches 2 --out audit
    python scripts/referee_audit.py --matches 1 --half 120 --samples 2 --json > calls.json
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

#: event types that are the referee's calls (its decisions), and the rule each belongs to
RULE_OF = {
    "goal": "goal",
    "goal_disallowed": "goal",
    "ball_out": "ball_out",
    "dribble_too_far": "dribbling",
    "dribble_backward_too_far": "dribbling",
    "goal_area": "goal_area",
    "penalty_area_crowded": "penalty_area",
    "penalty_area_time": "penalty_area",
    "set_piece_distance": "set_piece_distance",
    "kickoff_half": "kickoff_half",
    "dropped_ball_distance": "dropped_ball_distance",
    "restart_timeout": "restart_timeout",
    "double_touch": "double_touch",
    "charging": "charging",
    "pushing": "pushing",
    "goalkeeper_contact": "goalkeeper_contact",
    "lob": "lob",
    "ball_holding": "ball_holding",
    "ball_rotation": "ball_rotation",
    "no_progress": "no_progress",
    "yellow_card": "cards",
    "red_card": "cards",
    "send_off": "cards",
}
#: where the scene of a sample is set up from: the restart being prepared or taken, else play
RESTART_PHASES = ("prepare", "taking")


def rule_of(ev: dict) -> str:
    """The rule a call belongs to (a goal disallowed under RC-10.1.2 is own_half_regain's)."""
    if ev["type"] == "goal_disallowed" and "RC-10.1.2" in ev.get("detail", ""):
        return "own_half_regain"
    return RULE_OF[ev["type"]]


# --- one match ----------------------------------------------------------------------------------------------
def play_match(job: dict, progress=None) -> dict:
    """Play one match (in this process) and return every call with the situation it was made in."""
    import simatch
    from simatch import msgs
    from simatch.bus import topics

    overrides = {
        "teams.cyan.strategy": job["cyan"],
        "teams.magenta.strategy": job["magenta"],
        "match.half_duration": job["half"],
    }
    calls: list[dict] = []
    t0 = time.monotonic()
    with simatch.Simulation("msl_5v5", seed=job["seed"], overrides=overrides) as sim:
        ref = sim.judge

        def on_event(ev) -> None:
            if ev.type not in RULE_OF:
                return
            game = ref.m.game
            obs = ref.m.obs
            restart = game.restart if game.phase.value in RESTART_PHASES else None
            states = sim.model_states()
            calls.append(
                {
                    "t": round(float(ev.stamp), 3),
                    "type": ev.type,
                    "team": ev.team,
                    "robot": int(ev.robot),
                    "x": round(float(ev.x), 3),
                    "y": round(float(ev.y), 3),
                    "value": float(ev.value),
                    "limit": float(ev.limit),
                    "detail": ev.detail,
                    "stage": game.stage.name,
                    "clock": round(game.clock, 2),
                    "phase": game.phase.value,
                    "attacks": {t: obs.attacks(t) for t in obs.teams},
                    "restart": None
                    if restart is None
                    else {"kind": restart.kind, "team": restart.team, "x": float(restart.x), "y": float(restart.y)},
                    "robots": {
                        name: [round(float(s.x), 3), round(float(s.y), 3), round(float(s.yaw), 4)]
                        for name, s in states.items()
                        if name != "ball"
                    },
                    "ball": [round(float(states["ball"].x), 3), round(float(states["ball"].y), 3)],
                    "sent_off": [obs.names[i] for i in ref.discipline.sent_off],
                }
            )

        sim.bus.subscribe(topics.EVENTS, msgs.GameEvent, on_event)
        sim.run(progress=progress)
        result = sim.result()
    return {
        **job,
        "sim_seconds": result["sim_seconds"],
        "wall_seconds": round(time.monotonic() - t0, 1),
        "digest": result["state_digest"],
        "result": result["result"],
        "calls": calls,
    }


# --- the scene of a sample ----------------------------------------------------------------------------------
def scene_of(call: dict, match: dict, name: str) -> str:
    """A scene that sets up the situation of ``call`` (TOML text, with what was called in its header)."""
    from simatch.config.loader import load_scene

    base = load_scene("msl_5v5").spec
    what = f"value {call['value']:.4g} against limit {call['limit']:.4g}" if call["value"] or call["limit"] else ""
    who = f"{call['team']}/{call['robot']}" if call["robot"] else call["team"]
    original = (
        f"simatch run msl_5v5 --seed {match['seed']} --set teams.cyan.strategy={match['cyan']} "
        f"--set teams.magenta.strategy={match['magenta']} --set match.half_duration={match['half']:g} "
        f"--duration {math.ceil(call['t'] + 1.0)} --view"
    )
    lines = [
        f"# Referee audit sample: {call['type']} (rule {rule_of(call)}){' by ' + who if who else ''}, called at",
        f"# t = {call['t']:.3f} s ({call['stage']}, clock {call['clock']:.1f} s, {call['phase']}) in match "
        f"{match['index']} ({match['cyan']} cyan vs {match['magenta']} magenta, seed {match['seed']})"
        + (f": {what}" if what else ""),
        *_wrapped(f"the referee: {call['detail']}"),
        "# Every robot and the ball stand where they were at the call; the teams play on from there, the referee",
        "# judging (" + ("in play" if call["restart"] is None else f"the {call['restart']['kind']} being taken") + ").",
        "# Look at it:  simatch run THIS_FILE --view",
        "# The original match up to that moment:",
        f"#   {original}",
        f'name = "{name}"',
        f'description = "referee audit: {call["type"]} at t = {call["t"]:.1f} s of match {match["index"]} '
        f'(seed {match["seed"]})"',
        "",
        "[world]",
        f"length = {base.world.length!r}",
        f"width = {base.world.width!r}",
        "",
        "[ball]",
        f"position = [{call['ball'][0]!r}, {call['ball'][1]!r}]",
    ]
    for team in ("cyan", "magenta"):
        spec = base.teams[team]
        ids = spec.robot_ids()
        poses = ", ".join("[{!r}, {!r}, {!r}]".format(*call["robots"][f"{team}/{rid}"]) for rid in ids)
        lines += [
            "",
            f"[teams.{team}]",
            f'model = "{spec.model}"',
            f'strategy = "{match[team]}"',
            f"goalkeeper = {spec.goalkeeper}",
            f'attacks = "{call["attacks"][team]}"',
            f"start = [{poses}]",
        ]
    lines += [
        "",
        "[control]",
        f"period = {base.control.period!r}",
        "",
        "[judge]",
        'kind = "msl_referee"',
        "",
        "[match]",
        "halves = 1",
        "half_duration = 60.0",
        f'kickoff = "{base.match.kickoff}"',
    ]
    r = call["restart"]
    if r is None:
        lines.append('start = "play"')
    else:
        lines.append(f'start = "{r["kind"]}"')
        if r["team"]:
            lines.append(f'start_team = "{r["team"]}"')
        lines.append(f"start_spot = [{r['x']!r}, {r['y']!r}]")
    if call["sent_off"]:
        lines.insert(
            lines.index(f'name = "{name}"'),
            f"# (sent off at the time, here on the field: {', '.join(call['sent_off'])})",
        )
    return "\n".join(lines) + "\n"


def _wrapped(text: str, width: int = 110) -> list[str]:
    out, line = [], "#"
    for word in text.split():
        if len(line) + 1 + len(word) > width:
            out.append(line)
            line = "#  "
        line += " " + word
    out.append(line)
    return out


def samples(calls: list[tuple[dict, dict]], k: int) -> list[tuple[dict, dict]]:
    """Up to ``k`` of the calls, spread evenly over them (the first and the last among them)."""
    if len(calls) <= k:
        return list(calls)
    if k == 1:
        return [calls[0]]
    return [calls[round(i * (len(calls) - 1) / (k - 1))] for i in range(k)]


# --- the report -----------------------------------------------------------------------------------------------
def counts(matches: list[dict]) -> dict[str, list[int]]:
    """Calls per event type, one count per match (in the order of ``matches``)."""
    types = sorted({c["type"] for m in matches for c in m["calls"]}, key=lambda t: (RULE_OF[t], t))
    return {t: [sum(1 for c in m["calls"] if c["type"] == t) for m in matches] for t in types}


def markdown(matches: list[dict]) -> str:
    table = counts(matches)
    head = " | ".join(f"{m['index']}: {m['cyan']} v {m['magenta']}, seed {m['seed']}" for m in matches)
    lines = [f"| call (rule) | {head} | all |", "|---|" + "---|" * (len(matches) + 1)]
    for t, row in table.items():
        lines.append(f"| `{t}` ({RULE_OF[t]}) | " + " | ".join(map(str, row)) + f" | {sum(row)} |")
    score = " | ".join(f"{m['result']['score']['cyan']}:{m['result']['score']['magenta']}" for m in matches)
    lines.append(f"| score (cyan:magenta) | {score} | |")
    return "\n".join(lines)


def print_report(matches: list[dict], written: dict[str, list[str]]) -> None:
    table = counts(matches)
    print()
    for m in matches:
        s = m["result"]["score"]
        print(
            f"match {m['index']}: {m['cyan']} (cyan) vs {m['magenta']} (magenta), seed {m['seed']}: "
            f"{s['cyan']}:{s['magenta']}, {len(m['calls'])} calls, {m['sim_seconds']:.0f} s simulated in "
            f"{m['wall_seconds']:.0f} s wall"
        )
    print()
    width = max([len(t) for t in table] + [10])
    print(f"{'call':{width}s}  {'rule':20s}  " + "  ".join(f"m{m['index']:<3d}" for m in matches) + "  all")
    for t, row in table.items():
        print(f"{t:{width}s}  {RULE_OF[t]:20s}  " + "  ".join(f"{n:<4d}" for n in row) + f"  {sum(row)}")
    if written:
        print("\nsample situations (simatch run FILE --view):")
        for t, paths in written.items():
            print(f"  {t}: " + ", ".join(paths))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--matches", type=int, default=2, help="matches per pairing (default 2)")
    ap.add_argument("--half", type=float, default=900.0, help="length of each half [s] (default 900, as MSL)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--samples", type=int, default=3, help="sample situations written per call type (default 3)")
    ap.add_argument("--out", default="audit", help="folder for audit.json and scenarios/ (default ./audit)")
    ap.add_argument("--jobs", type=int, default=1, help="matches played at once, one process each (default 1)")
    ap.add_argument("--nice", type=int, default=10, help="lower this process's priority by this much (default 10)")
    ap.add_argument("--markdown", action="store_true", help="also print the counts as a Markdown table")
    ap.add_argument("--json", action="store_true", help="print one JSON object (counts, matches, calls) and no table")
    args = ap.parse_args(argv)
    if args.matches < 1 or args.half <= 0 or args.samples < 0 or args.jobs < 1:
        ap.error("--matches and --jobs must be at least 1, --half positive, --samples at least 0")
    if args.nice:
        os.nice(args.nice)
    jobs = []
    for pairing in ("nubot", "simple"):
        for k in range(args.matches):
            seed = args.first_seed + k
            nubot_cyan = pairing == "nubot" or k % 2 == 0
            jobs.append(
                {
                    "index": len(jobs) + 1,
                    "seed": seed,
                    "cyan": "nubot" if nubot_cyan else pairing,
                    "magenta": pairing if nubot_cyan else "nubot",
                    "half": args.half,
                }
            )
    matches = run_all(jobs, args.jobs, show=not args.json)
    out = Path(args.out)
    (out / "scenarios").mkdir(parents=True, exist_ok=True)
    by_type: dict[str, list[tuple[dict, dict]]] = {}
    for m in matches:
        for c in m["calls"]:
            by_type.setdefault(c["type"], []).append((c, m))
    written: dict[str, list[str]] = {}
    for t, calls in sorted(by_type.items()):
        for k, (c, m) in enumerate(samples(calls, args.samples), 1):
            path = out / "scenarios" / f"{t}_{k}.toml"
            path.write_text(scene_of(c, m, f"audit_{t}_{k}"), encoding="utf-8")
            c["scenario"] = str(path)
            written.setdefault(t, []).append(str(path))
    report = {
        "matches": [{k: v for k, v in m.items() if k != "calls"} for m in matches],
        "counts": counts(matches),
        "calls": [{**c, "match": m["index"]} for m in matches for c in m["calls"]],
    }
    (out / "audit.json").write_text(json.dumps(report, indent=1), encoding="utf-8")
    if args.json:
        json.dump(report, sys.stdout)
        print()
    else:
        print_report(matches, written)
        print(f"\nevery call with its situation: {out / 'audit.json'}")
    if args.markdown:
        print(markdown(matches))
    return 0


def run_all(jobs: list[dict], workers: int, show: bool) -> list[dict]:
    """Every match, with a progress bar on a terminal (simulated seconds, or matches when several run at once)."""
    total = sum(2 * j["half"] for j in jobs)
    bar = None
    if show and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=round(total), unit="sim s", file=sys.stderr, dynamic_ncols=True, desc="matches")
    try:
        if workers == 1:
            out = []
            for job in jobs:
                done = [0.0]

                def progress(t: float, done=done) -> None:
                    if bar is not None:
                        bar.update(t - done[0])
                        done[0] = t

                if bar is not None:
                    bar.set_postfix_str(f"match {job['index']}/{len(jobs)}: {job['cyan']} v {job['magenta']}")
                out.append(play_match(job, progress))
            return out
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(play_match, job) for job in jobs]
            out = []
            for f in futures:
                out.append(f.result())
                if bar is not None:
                    bar.update(2 * out[-1]["half"])
            return out
    finally:
        if bar is not None:
            bar.close()


if __name__ == "__main__":
    sys.exit(main())
