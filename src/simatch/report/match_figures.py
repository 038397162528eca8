"""The plots of a match report, each a Plotly figure made from the analysis (`MatchAnalysis.finish`).

Every field plot is in the report's view frame: the first team attacks to the right for the whole match.
"""

from __future__ import annotations

import plotly.graph_objects as go
from plotly.subplots import make_subplots

from .analysis import OUTCOMES
from .pitch import field_figure, field_from

#: readable shades for the usual team colour names (the scene's colour is used as it is otherwise)
SHADES = {
    "cyan": "#0094b8",
    "magenta": "#c2188f",
    "blue": "#1f5fd1",
    "yellow": "#d6a400",
    "red": "#d12a2a",
    "green": "#2e9e44",
    "orange": "#e07b00",
}
PALETTE = ["#0094b8", "#c2188f", "#e07b00", "#2e9e44", "#6a3fc1", "#8c564b"]
OUTCOME_SYMBOL = {
    "goal": "star",
    "disallowed": "star-open",
    "saved": "square",
    "blocked": "x",
    "team-mate": "circle-open",
    "off target": "triangle-up-open",
    "stopped": "diamond-open",
}
CATEGORY_ROWS = ["goals", "fouls", "cards", "restarts", "stages", "other"]
STAGE_COLOURS = {
    "first_half": "#9ecae1",
    "second_half": "#6baed6",
    "third_half": "#4292c6",
    "fourth_half": "#2171b5",
    "half_time": "#e0e0e0",
    "penalty_shootout": "#fdae6b",
    "ended": "#bdbdbd",
}
PHASE_COLOURS = {
    "play": "#41ab5d",
    "stopped": "#ef6548",
    "prepare": "#fdb863",
    "taking": "#ffd92f",
    "paused": "#969696",
    "ended": "#bdbdbd",
}


def team_colours(stats: dict) -> dict[str, str]:
    out = {}
    for k, t in enumerate(stats["meta"]["teams"]):
        colour = str(t.get("colour") or t["name"])
        out[t["name"]] = SHADES.get(colour.lower(), colour if colour.startswith("#") else PALETTE[k % len(PALETTE)])
    return out


def team_title(stats: dict, team: str) -> str:
    for t in stats["meta"]["teams"]:
        if t["name"] == team:
            return f"{team} ({t['label']})"
    return team


def _base(fig: go.Figure, height: int, title: str = "") -> go.Figure:
    fig.update_layout(
        template="plotly_white",
        height=height,
        margin=dict(l=60, r=20, t=40 if title else 20, b=40),
        title=dict(text=title, x=0.01, xanchor="left") if title else None,
        legend=dict(orientation="h", yanchor="bottom", y=1.02, xanchor="right", x=1),
    )
    return fig


def direction_note(stats: dict) -> str:
    """Which way the field plots are drawn: the first team attacks to the right."""
    first = stats["meta"]["teams"][0]["name"]
    changed = len(stats.get("sides", [])) > 1
    tail = " (mirrored after the change of ends)" if changed else ""
    return f"{first} attacks → throughout{tail}"


# --- field plots ---------------------------------------------------------------------------------------------
def heat_map(stats: dict, key: str) -> go.Figure:
    """Seconds spent per 0.5 m cell during play: the ball, or one team's robots together."""
    f = field_from(stats["meta"]["field"])
    heat = stats["heat"]
    colours = team_colours(stats)
    title = "ball" if key == "ball" else team_title(stats, key)
    fig = field_figure(f, title, style="light")  # (the section says which way: `direction_note`)
    z = heat["maps"].get(key)
    if z is None:
        return fig
    xe, ye = heat["x_edges"], heat["y_edges"]
    xc = [(a + b) / 2 for a, b in zip(xe, xe[1:])]
    yc = [(a + b) / 2 for a, b in zip(ye, ye[1:])]
    tint = _rgb(colours.get(key, "#e07b00")) if key != "ball" else "224,123,0"
    cells = sorted(v for row in z for v in row if v > 0)
    # the colour saturates at the 95th percentile: a goalkeeper standing on its line would wash out the rest
    top = cells[min(len(cells) - 1, int(0.95 * len(cells)))] if cells else 1.0
    fig.add_trace(
        go.Heatmap(
            x=xc,
            y=yc,
            z=[[v if v > 0 else None for v in row] for row in z],
            zmin=0,
            zmax=max(top, 1e-6),
            colorscale=[[0.0, f"rgba({tint},0.12)"], [0.5, f"rgba({tint},0.6)"], [1.0, "rgba(90,0,20,0.95)"]],
            colorbar=dict(title="s", thickness=12, len=0.8),
            hovertemplate="x %{x:.2f} m, y %{y:.2f} m: %{z:.2f} s<extra></extra>",
            name=key,
        )
    )
    return fig


def shot_map(stats: dict) -> go.Figure:
    """Every shot from where it was taken, a line to where its path met the goal line, its outcome."""
    f = field_from(stats["meta"]["field"])
    colours = team_colours(stats)
    fig = field_figure(f, f"shots: origin and outcome ({direction_note(stats)})", height=460)
    fig.update_layout(showlegend=True, legend=dict(orientation="h", y=-0.02, yanchor="top", x=0.0))
    shots = stats["shots"]
    for team in [t["name"] for t in stats["meta"]["teams"]]:
        mine = [s for s in shots if s["team"] == team]
        if not mine:
            continue
        xs, ys = [], []
        for s in mine:
            xs += [s["x"], s["goal_x"], None]
            ys += [s["y"], s["goal_y"], None]
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines",
                line=dict(color=colours[team], width=1, dash="dot"),
                hoverinfo="skip",
                showlegend=False,
            )
        )
        for outcome in OUTCOMES:
            these = [s for s in mine if s["outcome"] == outcome]
            if not these:
                continue
            fig.add_trace(
                go.Scatter(
                    x=[s["x"] for s in these],
                    y=[s["y"] for s in these],
                    mode="markers",
                    name=f"{team}: {outcome} ({len(these)})",
                    marker=dict(
                        symbol=OUTCOME_SYMBOL[outcome],
                        size=14 if outcome == "goal" else 11,
                        color=colours[team],
                        line=dict(color="white", width=1.5),
                    ),
                    text=[
                        f"{s['robot']} at {s['t']:.1f} s, {s['speed']:.1f} m/s{' lob' if s['lob'] else ''}, "
                        f"{s['distance']:.1f} m out: {outcome}<br>{_short(s['detail'])}"
                        for s in these
                    ],
                    hovertemplate="%{text}<extra></extra>",
                    meta={"shots": len(these), "team": team, "outcome": outcome},
                )
            )
    return fig


# --- time plots ----------------------------------------------------------------------------------------------
def timeline(stats: dict) -> go.Figure:
    """The score over time (top) and every event by kind (bottom), the reason in each marker's hover text."""
    colours = team_colours(stats)
    teams = [t["name"] for t in stats["meta"]["teams"]]
    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, row_heights=[0.4, 0.6], vertical_spacing=0.06)
    end = stats["duration"]
    for team in teams:
        ts, goals = [], []
        for point in stats["score_timeline"]:
            ts.append(point["t"])
            goals.append(point["score"][team])
        ts.append(end)
        goals.append(goals[-1])
        fig.add_trace(
            go.Scatter(
                x=ts,
                y=goals,
                mode="lines",
                line_shape="hv",
                name=f"{team} goals",
                line=dict(color=colours[team], width=3),
            ),
            row=1,
            col=1,
        )
    rows_used = [c for c in CATEGORY_ROWS if any(ev["category"] == c for ev in stats["events"])]
    for cat in rows_used:
        evs = [ev for ev in stats["events"] if ev["category"] == cat]
        fig.add_trace(
            go.Scatter(
                x=[ev["t"] for ev in evs],
                y=[cat] * len(evs),
                mode="markers",
                name=cat,
                showlegend=False,
                marker=dict(
                    size=10 if cat in ("goals", "cards") else 8,
                    color=[colours.get(ev.get("team", ""), "#666666") for ev in evs],
                    symbol="diamond" if cat == "goals" else "circle",
                    line=dict(color="white", width=1),
                ),
                text=[
                    f"{ev['t']:.2f} s {ev['type']}{' ' + ev['team'] if ev.get('team') else ''}<br>"
                    f"{_short(ev.get('detail', ''))}"
                    for ev in evs
                ],
                hovertemplate="%{text}<extra></extra>",
            ),
            row=2,
            col=1,
        )
    for st in stats["stages"]:
        if st["stage"] in ("half_time", "penalty_shootout"):
            fig.add_vrect(x0=st["t0"], x1=st["t1"], fillcolor="#dddddd", opacity=0.35, line_width=0)
    most = max((max(p["score"].values(), default=0) for p in stats["score_timeline"]), default=0)
    fig.update_yaxes(title_text="goals", dtick=max(1, -(-most // 6)), rangemode="tozero", row=1, col=1)
    fig.update_yaxes(categoryorder="array", categoryarray=list(reversed(rows_used)), row=2, col=1)
    fig.update_xaxes(title_text="simulated time [s]", row=2, col=1)
    return _base(fig, 420 + 18 * len(rows_used), "score and events (hover a marker for the referee's reason)")


def possession(stats: dict) -> go.Figure:
    """Each team's share of the ball-in-play time per time bin, and over the match."""
    colours = team_colours(stats)
    pos = stats["possession"]
    teams = [t["name"] for t in stats["meta"]["teams"]]
    fig = make_subplots(
        rows=1,
        cols=2,
        column_widths=[0.8, 0.2],
        horizontal_spacing=0.08,
        subplot_titles=(f"share of play per {pos['bin_seconds']:g} s", "whole match"),
    )
    mids = [(b["t0"] + b["t1"]) / 2 for b in pos["bins"]]
    widths = [b["t1"] - b["t0"] for b in pos["bins"]]
    for team in teams:
        share = [(b["share"][team] * 100 if b["share"][team] is not None else None) for b in pos["bins"]]
        fig.add_trace(
            go.Bar(
                x=mids,
                y=share,
                width=widths,
                name=team,
                marker_color=colours[team],
                customdata=[b["seconds"][team] for b in pos["bins"]],
                hovertemplate=team + ": %{y:.0f} % (%{customdata:.1f} s)<extra></extra>",
            ),
            row=1,
            col=1,
        )
        total = pos["share"][team]
        fig.add_trace(
            go.Bar(
                x=["match"],
                y=[total * 100 if total is not None else 0],
                name=team,
                showlegend=False,
                marker_color=colours[team],
                text=[f"{total * 100:.0f} %" if total is not None else "-"],
                textposition="inside",
                hovertemplate=team + ": %{y:.1f} %<extra></extra>",
            ),
            row=1,
            col=2,
        )
    fig.update_layout(barmode="stack", bargap=0.05)
    _base(fig, 340, "possession (the team that last touched the ball alone has it)")
    fig.update_layout(legend=dict(x=0.76))  # above the bins, clear of the whole match's title
    fig.update_yaxes(range=[0, 100], title_text="% of play", row=1, col=1)
    fig.update_yaxes(range=[0, 100], row=1, col=2)
    fig.update_xaxes(title_text="simulated time [s]", row=1, col=1)
    return fig


def stages(stats: dict) -> go.Figure:
    """The match's stages and, below, the phases of play (play, stopped, prepare, taking)."""
    fig = go.Figure()
    for row, key, colours in (("stage", "stages", STAGE_COLOURS), ("phase", "phases", PHASE_COLOURS)):
        seen = set()
        for seg in stats[key]:
            name = seg[row]
            if seg["t1"] <= seg["t0"] and name == "ended":
                continue
            fig.add_trace(
                go.Bar(
                    x=[max(seg["t1"] - seg["t0"], 1e-3)],
                    y=[row],
                    base=[seg["t0"]],
                    orientation="h",
                    name=name,
                    legendgroup=name,
                    showlegend=name not in seen,
                    marker_color=colours.get(name, "#999999"),
                    hovertemplate=f"{name}: %{{base:.1f}} s to {seg['t1']:.1f} s<extra></extra>",
                )
            )
            seen.add(name)
    fig.update_layout(barmode="overlay", bargap=0.3)
    fig.update_yaxes(categoryorder="array", categoryarray=["phase", "stage"])
    fig.update_xaxes(title_text="simulated time [s]")
    return _base(fig, 260, "game stages and phases of play")


# --- robots --------------------------------------------------------------------------------------------------
def robots(stats: dict) -> go.Figure:
    """Distance run and top speed of every robot."""
    colours = team_colours(stats)
    rows = [r for r in stats["robots"] if r["team"]]
    names = [r["name"] for r in rows]
    fig = make_subplots(rows=1, cols=2, subplot_titles=("distance run [m]", "top speed [m/s]"), horizontal_spacing=0.1)
    for col, key in ((1, "distance"), (2, "top_speed")):
        fig.add_trace(
            go.Bar(
                x=names,
                y=[r[key] for r in rows],
                marker_color=[colours.get(r["team"], "#888") for r in rows],
                text=[f"{r[key]:.1f}" if key == "distance" else f"{r[key]:.2f}" for r in rows],
                textposition="outside",
                showlegend=False,
                hovertemplate="%{x}: %{y:.2f}<extra></extra>",
                name=key,
            ),
            row=1,
            col=col,
        )
    return _base(fig, 360, "per robot")


def roles(stats: dict) -> go.Figure:
    """Seconds each robot spent in each role it announced in its StrategyInfo."""
    role_time = stats["roles"]
    robots_ = list(role_time)
    names = sorted({role for r in role_time.values() for role in r})
    fig = go.Figure()
    for role in names:
        fig.add_trace(
            go.Bar(
                y=robots_,
                x=[role_time[r].get(role, 0.0) for r in robots_],
                orientation="h",
                name=role,
                hovertemplate="%{y} " + role + ": %{x:.1f} s<extra></extra>",
            )
        )
    fig.update_layout(barmode="stack")
    fig.update_yaxes(autorange="reversed")
    fig.update_xaxes(title_text="seconds")
    return _base(fig, 120 + 26 * max(1, len(robots_)), "role time per robot (from StrategyInfo)")


def _rgb(colour: str) -> str:
    c = colour.lstrip("#")
    if len(c) == 6:
        return ",".join(str(int(c[i : i + 2], 16)) for i in (0, 2, 4))
    return "255,136,0"


def _short(text: str, n: int = 160) -> str:
    return text if len(text) <= n else text[: n - 1] + "…"
