"""The match report: one HTML page a coach reads at a glance (``simatch report FILE.mcap -o report.html``,
``simatch run ... --report report.html``, and each match of a tournament with ``--report DIR``).

From the top: the score and the few numbers per team, the score and event timeline (every marker's reason on
hover, and the table of goals, fouls, cards and restarts below it), possession over time, the shot map, heat
maps of the ball and of each team, distance and top speed per robot, role time per robot, the game's stages.
"""

from __future__ import annotations

import html
from pathlib import Path

from . import match_figures as mf
from .page import Page, Raw, swatch, table

KEY_EVENTS = frozenset({"goals", "fouls", "cards", "restarts"})


def _teams(stats: dict) -> list[dict]:
    return stats["meta"]["teams"]


def heading(stats: dict) -> str:
    teams = _teams(stats)
    colours = mf.team_colours(stats)
    score = stats["score_timeline"][-1]["score"]
    names = [
        f'<span class="swatch" style="background:{colours[t["name"]]}"></span>{html.escape(t["name"])} '
        f'<span style="color:#c9d3df">({html.escape(t["label"])})</span>'
        for t in teams
    ]
    goals = " : ".join(str(score.get(t["name"], 0)) for t in teams)
    if len(teams) == 2:
        return (
            f'<div style="display:flex;gap:28px;align-items:center;margin-top:10px">'
            f'<div style="font-size:20px">{names[0]}</div><div class="score" id="final-score">{goals}</div>'
            f'<div style="font-size:20px">{names[1]}</div></div>'
        )
    return f'<div class="score" id="final-score">{goals}</div><div>{" · ".join(names)}</div>'


def subtitle(stats: dict) -> str:
    meta = stats["meta"]
    parts = [f"scene {meta['scene']}", f"seed {meta['seed']}", f"{stats['duration']:.1f} s simulated"]
    if stats.get("state_digest"):
        parts.append(f"state digest {stats['state_digest'][:16]}…")
    rec = stats.get("recording")
    if rec:
        parts.append(f"recording {Path(rec['path']).name} ({rec['status']})")
    return " · ".join(parts)


def numbers_table(stats: dict) -> str:
    teams = [t["name"] for t in _teams(stats)]
    colours = mf.team_colours(stats)
    summary = stats["summary"]
    rows, keys = [], []
    fields = [
        ("goals", "goals", "{}"),
        ("shots", "shots", "{}"),
        ("on target", "on_target", "{}"),
        ("possession", "possession", "pct"),
        ("fouls", "fouls", "{}"),
        ("yellow cards", "yellow_cards", "{}"),
        ("red cards", "red_cards", "{}"),
        ("distance run [m]", "distance", "{:.1f}"),
    ]
    if any(summary[t]["strategy_errors"] for t in teams):
        fields.append(("strategy errors", "strategy_errors", "{}"))
    for team in teams:
        s = summary[team]
        row = [swatch(colours[team], mf.team_title(stats, team))]
        key = [""]
        for _, k, fmt in fields:
            v = s[k]
            if fmt == "pct":
                row.append("-" if v is None else f"{v * 100:.1f} %")
            else:
                row.append(fmt.format(v))
            key.append(f"{team}.{k}")
        rows.append(row)
        keys.append(key)
    return table(["team"] + [f[0] for f in fields], rows, keys=keys)


def events_table(stats: dict) -> str:
    evs = [ev for ev in stats["events"] if ev["category"] in KEY_EVENTS and ev["type"] not in ("ball_placed",)]
    important = [ev for ev in evs if ev["category"] != "restarts"]
    restarts = [ev for ev in evs if ev["category"] == "restarts"]

    def rows(items):
        return [
            [f"{ev['t']:.2f}", ev["type"], ev.get("team", ""), ev.get("robot", ""), _measure(ev), _wrap(ev)]
            for ev in items
        ]

    header = ["t [s]", "event", "team", "robot", "measured / limit", "reason"]
    out = table(header, rows(important), left=0, css="events") if important else "<p>no goal, foul or card</p>"
    if restarts:
        out += (
            f"<details><summary>{len(restarts)} restarts and balls out, with their reasons</summary>"
            f"{table(header, rows(restarts), left=0)}</details>"
        )
    return out


def _measure(ev: dict) -> str:
    if "value" not in ev:
        return ""
    return f"{ev['value']:.3g} / {ev['limit']:.3g}"


def _wrap(ev: dict) -> Raw:
    return Raw(f'<span class="wrap">{html.escape(ev.get("detail", ""))}</span>')


def shots_table(stats: dict) -> str:
    shots = stats["shots"]
    if not shots:
        return "<p>no shot</p>"
    rows = [
        [
            f"{s['t']:.2f}",
            s["robot"],
            f"{s['distance']:.1f}",
            f"{s['speed']:.1f}",
            "lob" if s["lob"] else "ground",
            s["outcome"],
        ]
        for s in shots
    ]
    header = ["t [s]", "robot", "distance [m]", "speed [m/s]", "kick", "outcome"]
    return f"<details><summary>every shot</summary>{table(header, rows, left=0)}</details>"


def build(stats: dict, title: str | None = None) -> Page:
    teams = [t["name"] for t in _teams(stats)]
    if title is None:
        labels = [f"{t['name']} ({t['label']})" for t in _teams(stats)]
        title = " vs ".join(labels) if len(labels) == 2 else stats["meta"]["scene"]
    back = ""
    if stats.get("tournament"):
        t = stats["tournament"]
        back = (
            f'<div style="margin-top:8px"><a style="color:#9cd0ff" href="{html.escape(t["index"])}">'
            f"← the tournament</a> · {html.escape(t['stage'])}</div>"
        )
    page = Page(title, subtitle(stats), heading(stats) + back)
    problems = (stats.get("recording") or {}).get("problems") or []
    warn = "".join(f'<p class="failed">{html.escape(p)}</p>' for p in problems)
    page.section("the match in numbers", warn + numbers_table(stats), anchor="numbers")
    page.section(
        "score and events",
        page.figure(mf.timeline(stats), "timeline") + events_table(stats),
        note="Top: goals over time. Below: every event by kind, coloured by team; hover a marker for what the "
        "referee measured and decided. Grey bands: breaks.",
        anchor="timeline",
    )
    page.section(
        "possession",
        page.figure(mf.possession(stats), "possession"),
        note="Counted while the ball is in play: the team whose robots last touched the ball alone has it "
        "(a duel leaves it where it was).",
        anchor="possession",
    )
    page.section(
        "shots",
        page.figure(mf.shot_map(stats), "shots") + shots_table(stats),
        note="A shot is a kick whose ball heads for the goal the kicker's team attacks (within 1 m of a post), "
        "from within 11 m of that goal line, fast enough to roll there. Symbol: outcome; dotted line: where its "
        "path met the goal line.",
        anchor="shots",
    )
    heat = "".join(
        f"<div>{page.figure(mf.heat_map(stats, key), f'heat-{key}')}</div>"
        for key in ["ball", *teams]
        if key in stats["heat"]["maps"]
    )
    page.section(
        "where the play was",
        f'<div class="grid2">{heat}</div>',
        note="Seconds spent in each 0.5 m cell while the ball was in play; a team's map adds up all its robots "
        f"({mf.direction_note(stats)}).",
        anchor="heat",
    )
    page.section("robots", page.figure(mf.robots(stats), "robots"), anchor="robots")
    if stats["roles"]:
        page.section(
            "roles",
            page.figure(mf.roles(stats), "roles"),
            note="The role each robot announced in its StrategyInfo, in seconds (teams whose strategies publish "
            "no StrategyInfo are missing).",
            anchor="roles",
        )
    if stats["stages"]:
        page.section("game stages", page.figure(mf.stages(stats), "stages"), anchor="stages")
    return page


def write_match_report(stats: dict, path: str | Path, plotly_js: str = "inline", title: str | None = None) -> Path:
    """Write the report of a match (its analysis: `MatchAnalysis.finish`) at ``path``."""
    return build(stats, title).write(path, stats, plotly_js)
