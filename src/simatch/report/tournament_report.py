"""The tournament report: ``DIR/index.html`` (``simatch tournament ... --report DIR``), beside the match reports
in ``DIR/matches/`` and one shared copy of Plotly's JavaScript (the folder opens with no network).

From the top: the standing (points, goal difference, Elo with its interval), the Elo ratings as a plot, the
head-to-head matrix, the score distribution of every pairing, the bracket of a knockout or the places after
each matchday of a league, the failed matches with their errors, and every match with a link to its report.

It draws what the tournament computed (`simatch.tournament.standing`): plain data in, pages out.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import plotly.graph_objects as go
from plotly.subplots import make_subplots

from .match_figures import PALETTE
from .page import PLOTLY_FILE, Page, Raw, link, table, write_plotly_js

WIN, DRAW, LOSS = "#2e9e44", "#9e9e9e", "#d12a2a"


def _base(fig: go.Figure, height: int, title: str) -> go.Figure:
    fig.update_layout(
        template="plotly_white",
        height=height,
        margin=dict(l=60, r=20, t=50, b=40),
        title=dict(text=title, x=0.01, xanchor="left"),
    )
    return fig


def elo_figure(summary: dict) -> go.Figure:
    rows = sorted(summary["standing"], key=lambda t: t["elo"])
    fig = go.Figure(
        go.Scatter(
            x=[t["elo"] for t in rows],
            y=[t["team"] for t in rows],
            mode="markers",
            marker=dict(size=12, color="#1f5fd1"),
            error_x=dict(
                type="data",
                symmetric=False,
                array=[t["elo_high"] - t["elo"] for t in rows],
                arrayminus=[t["elo"] - t["elo_low"] for t in rows],
                thickness=2,
                width=6,
            ),
            customdata=[[t["elo_low"], t["elo_high"]] for t in rows],
            hovertemplate="%{y}: %{x:.0f} (95 %: %{customdata[0]:.0f} to %{customdata[1]:.0f})<extra></extra>",
        )
    )
    fig.add_vline(x=1500, line_dash="dot", line_color="#888")
    fig.update_xaxes(title_text="Elo rating (mean 1500); bars: 95 % interval (seeds resampled, at least the fit's own)")
    return _base(fig, 140 + 40 * len(rows), "Elo rating")


def head_to_head_figure(summary: dict) -> go.Figure:
    teams = [t["team"] for t in summary["standing"]]
    h2h = summary["head_to_head"]
    z, text = [], []
    for a in teams:
        zr, tr = [], []
        for b in teams:
            h = h2h.get(a, {}).get(b)
            if a == b or not h or not h["played"]:
                zr.append(None)
                tr.append("")
            else:
                zr.append(round(h["points"] / h["played"], 3))
                tr.append(f"{h['won']}-{h['drawn']}-{h['lost']}<br>{h['goals_for']}:{h['goals_against']}")
        z.append(zr)
        text.append(tr)
    fig = go.Figure(
        go.Heatmap(
            z=z,
            x=teams,
            y=teams,
            text=text,
            texttemplate="%{text}",
            zmin=0,
            zmax=3,
            colorscale=[[0, "#f4a582"], [0.5, "#f7f7f7"], [1, "#92c5de"]],
            colorbar=dict(title="points<br>per match", thickness=12),
            hovertemplate="%{y} against %{x}: %{z:.2f} points a match<br>won-drawn-lost %{text}<extra></extra>",
        )
    )
    fig.update_yaxes(autorange="reversed", title_text="team")
    fig.update_xaxes(title_text="against", side="top")
    size = 160 + 70 * len(teams)
    return _base(fig, size, "head to head (row against column): won-drawn-lost, goals")


def scores_figure(summary: dict) -> go.Figure | None:
    scores = summary["scores"]
    if not scores:
        return None
    pairs = list(scores)
    cols = min(3, len(pairs))
    rows = math.ceil(len(pairs) / cols)
    fig = make_subplots(
        rows=rows, cols=cols, subplot_titles=pairs, vertical_spacing=0.55 / max(rows, 1), horizontal_spacing=0.06
    )
    for k, pair in enumerate(pairs):
        counts = scores[pair]

        def key(s: str):
            a, b = (int(x) for x in s.split("-"))
            return (a - b, a)

        lines = sorted(counts, key=key)
        colours = [WIN if key(s)[0] > 0 else DRAW if key(s)[0] == 0 else LOSS for s in lines]
        fig.add_trace(
            go.Bar(
                x=lines,
                y=[counts[s] for s in lines],
                marker_color=colours,
                showlegend=False,
                hovertemplate=pair + ": %{x} in %{y} match(es)<extra></extra>",
                name=pair,
            ),
            row=k // cols + 1,
            col=k % cols + 1,
        )
    fig.update_yaxes(rangemode="tozero", dtick=1 if max(max(c.values()) for c in scores.values()) <= 10 else None)
    fig.update_xaxes(type="category")
    return _base(fig, 80 + 240 * rows, "score distribution per pairing (score of the first-named team first)")


def progression_figure(summary: dict) -> go.Figure | None:
    prog = summary.get("progression")
    if not prog or not prog["matchdays"]:
        return None
    fig = go.Figure()
    for k, (team, places) in enumerate(prog["places"].items()):
        fig.add_trace(
            go.Scatter(
                x=list(range(1, len(places) + 1)),
                y=places,
                mode="lines+markers",
                name=team,
                line=dict(color=PALETTE[k % len(PALETTE)], width=3),
            )
        )
    fig.update_yaxes(autorange="reversed", dtick=1, title_text="place")
    fig.update_xaxes(title_text="matchday", dtick=1)
    return _base(fig, 360, "place after each matchday")


#: the standing's columns: (header, key of the cell for tests and scripts, the cell from a team's row)
STANDING = [
    ("team", "", lambda t: t["team"]),
    ("played", "played", lambda t: t["played"]),
    ("won", "won", lambda t: t["won"]),
    ("drawn", "drawn", lambda t: t["drawn"]),
    ("lost", "lost", lambda t: t["lost"]),
    ("goals", "goals", lambda t: f"{t['goals_for']}:{t['goals_against']}"),
    ("diff", "diff", lambda t: f"{t['goal_difference']:+d}"),
    ("points", "points", lambda t: t["points"]),
    ("Elo", "elo", lambda t: f"{t['elo']:.0f}"),
    ("95 % interval", "interval", lambda t: f"{t['elo_low']:.0f} to {t['elo_high']:.0f}"),
    ("possession", "possession", lambda t: "-" if t["possession"] is None else f"{t['possession'] * 100:.1f} %"),
    ("shots (on target)", "shots", lambda t: f"{t['shots']} ({t['on_target']})"),
    ("failed", "failed", lambda t: Raw(f'<span class="failed">{t["failed"]}</span>') if t["failed"] else 0),
]


def standing_table(summary: dict) -> str:
    rows = [[t["rank"]] + [cell(t) for _, _, cell in STANDING] for t in summary["standing"]]
    keys = [[""] + [f"{t['team']}.{key}" if key else "" for _, key, _ in STANDING] for t in summary["standing"]]
    return table(["#"] + [h for h, _, _ in STANDING], rows, left=2, keys=keys)


def bracket_html(summary: dict) -> str:
    detail = summary.get("format_detail") or {}
    if detail.get("format") != "knockout":
        return ""
    parts = []
    for rnd in detail["rounds"]:
        rows = []
        for t in rnd:
            rows.append(
                [t["tie"], t["a"] or "(bye)", t["b"] or "(bye)", t["score"], t["winner"] or "(to play)", t["how"]]
            )
        parts.append(table(["tie", "higher seed", "lower seed", "aggregate", "goes on", "how"], rows, left=6))
    champion = detail.get("champion")
    head = f"<p><b>champion: {html.escape(champion)}</b></p>" if champion else ""
    return head + "".join(parts)


def matches_table(rows: list[dict]) -> str:
    header = ["stage", "seed", "home", "score", "away", "status", "report", "recording", "digest"]
    body = []
    for r in rows:
        score = f"{r['home_goals']} : {r['away_goals']}" if r["status"] == "ok" else "-"
        rep = link(r["report"], "report") if r.get("report") else ""
        rec = html.escape(Path(r["recording"]).name) if r.get("recording") else ""
        status = r["status"] if r["status"] == "ok" else Raw(f'<span class="failed">{html.escape(r["status"])}</span>')
        body.append(
            [
                r["stage"],
                r["seed"],
                f"{r['home']} ({r['home_colour']})",
                score,
                f"{r['away']} ({r['away_colour']})",
                status,
                rep,
                Raw(rec),
                (r.get("state_digest") or "")[:12],
            ]
        )
    return table(header, body, left=len(header))


def failed_table(summary: dict) -> str:
    if not summary["failed"]:
        return ""
    rows = [
        [
            f["stage"],
            f["seed"],
            f["home"],
            f["away"],
            f["status"],
            Raw(f'<span class="wrap">{html.escape(f["error"] or "")}</span>'),
        ]
        for f in summary["failed"]
    ]
    return table(["stage", "seed", "home", "away", "status", "error"], rows, left=6)


def build(summary: dict, rows: list[dict]) -> Page:
    t = summary["tournament"]
    m = summary["matches"]
    leader = summary["standing"][0]["team"] if summary["standing"] and m["played"] else None
    champion = (summary.get("format_detail") or {}).get("champion")
    state = "complete" if summary["complete"] else f"{m['missing']} match(es) still to play"
    title = f"{t['format']} of {len(t['teams'])} teams on {t['scene']}"
    sub = (
        f"{len(t['seeds'])} seed(s), both colours · {m['played']} played, {m['failed']} failed · {state}"
        f" · results {Path(t['out']).name}/matches.parquet"
    )
    best = champion or leader
    heading = (
        f'<div class="score" style="font-size:28px">{"champion" if champion else "leader"}: {html.escape(best)}</div>'
        if best
        else ""
    )
    page = Page(title, sub, heading)
    page.section(
        "standing",
        standing_table(summary),
        anchor="standing",
        note="Win 3 points, draw 1. Ordered by points, goal difference, goals, Elo. Failed matches count for nobody.",
    )
    page.section(
        "Elo",
        page.figure(elo_figure(summary), "elo"),
        anchor="elo",
        note=f"Maximum-likelihood Elo over every match; the interval comes from resampling the "
        f"{summary['elo_seeds']} seed(s), widened to at least the fit's own (±1.96 standard errors), which "
        "resampling cannot show when every seed gave the same results.",
    )
    page.section("head to head", page.figure(head_to_head_figure(summary), "h2h"), anchor="h2h")
    fig = scores_figure(summary)
    if fig is not None:
        page.section(
            "scores",
            page.figure(fig, "scores"),
            anchor="scores",
            note="Green: the first-named team won; grey: draw; red: it lost.",
        )
    bracket = bracket_html(summary)
    if bracket:
        page.section("bracket", bracket, anchor="bracket")
    fig = progression_figure(summary)
    if fig is not None:
        page.section("league table over the matchdays", page.figure(fig, "progression"), anchor="progression")
    failed = failed_table(summary)
    if failed:
        page.section(
            "failed matches",
            failed,
            anchor="failed",
            note="A match whose code raised, ran past its time limit, or whose worker died. "
            "`--retry-failed` plays them again.",
        )
    page.section("matches", matches_table(rows), anchor="matches")
    return page


def write_tournament_report(summary: dict, rows: list[dict], folder: str | Path) -> Path:
    folder = Path(folder)
    write_plotly_js(folder)
    return build(summary, rows).write(folder / "index.html", summary, plotly_js=PLOTLY_FILE)
