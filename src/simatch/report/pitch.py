"""The field drawn as Plotly shapes, from the one `FieldGeometry` the referee judges (lines, areas, goals,
boards), so that a heat map or a shot map sits on the field the match was played on."""

from __future__ import annotations

import math

import plotly.graph_objects as go

from ..field import FieldGeometry

#: (outside the lines, inside, lines, goals, boards): grass for markers, light under a heat map
STYLES = {
    "grass": ("#2f6a2f", "#3b7d3b", "rgba(255,255,255,0.9)", "rgba(255,255,255,0.25)", "#1d3d1d"),
    "light": ("#e9eee9", "#f7faf7", "rgba(60,80,60,0.75)", "rgba(60,80,60,0.12)", "#7d8c7d"),
}


def field_from(described: dict) -> FieldGeometry:
    """A FieldGeometry back from its `describe()` (as a report keeps it)."""
    keys = FieldGeometry.__dataclass_fields__
    return FieldGeometry(**{k: v for k, v in described.items() if k in keys and k not in ("areas",)})


def _path(points) -> str:
    head, *rest = points
    return f"M {head[0]:.3f} {head[1]:.3f} " + " ".join(f"L {x:.3f} {y:.3f}" for x, y in rest)


def _arc(cx: float, cy: float, r: float, a0: float, a1: float, n: int = 48) -> str:
    steps = max(4, int(n * abs(a1 - a0) / (2 * math.pi)))
    return _path(
        [
            (cx + r * math.cos(a0 + (a1 - a0) * k / steps), cy + r * math.sin(a0 + (a1 - a0) * k / steps))
            for k in range(steps + 1)
        ]
    )


def shapes(f: FieldGeometry, style: str = "grass", layer: str = "above") -> list[dict]:
    """Shapes of the field: the floor (below everything), markings, goals and boards (on ``layer``)."""
    L, W = f.half_length, f.half_width
    hx, hy = L + f.margin, W + f.margin
    outside, inside, colour, goal_fill, boards = STYLES[style]
    lw = 1.6
    out: list[dict] = [
        dict(type="rect", x0=-hx, y0=-hy, x1=hx, y1=hy, fillcolor=outside, line_width=0, layer="below"),
        dict(type="rect", x0=-L, y0=-W, x1=L, y1=W, fillcolor=inside, line_width=0, layer="below"),
    ]
    line = dict(color=colour, width=lw)
    for item in f.lines():
        if item["kind"] == "polyline":
            out.append(dict(type="path", path=_path(item["points"]), line=line, layer=layer))
        elif item["kind"] == "arc":
            cx, cy = item["center"]
            out.append(
                dict(type="path", path=_arc(cx, cy, item["radius"], item["start"], item["end"]), line=line, layer=layer)
            )
        elif item["kind"] == "dot":
            cx, cy = item["center"]
            r = item["radius"]
            out.append(
                dict(
                    type="circle",
                    x0=cx - r,
                    y0=cy - r,
                    x1=cx + r,
                    y1=cy + r,
                    fillcolor=colour,
                    line_width=0,
                    layer=layer,
                )
            )
    if f.goals:
        g = 0.5 * f.goal_width
        for side in (-1, 1):
            x0, x1 = side * L, side * (L + f.goal_depth)
            out.append(
                dict(
                    type="rect",
                    x0=min(x0, x1),
                    x1=max(x0, x1),
                    y0=-g,
                    y1=g,
                    line=dict(color=colour, width=2),
                    fillcolor=goal_fill,
                    layer=layer,
                )
            )
    if f.walls:
        out.append(dict(type="rect", x0=-hx, y0=-hy, x1=hx, y1=hy, line=dict(color=boards, width=3), layer=layer))
    return out


def field_figure(f: FieldGeometry, title: str = "", height: int = 430, style: str = "grass") -> go.Figure:
    """An empty figure of the field, x to the right and y up, one metre the same length on both axes."""
    hx, hy = f.half_length + f.margin, f.half_width + f.margin
    fig = go.Figure()
    fig.update_layout(
        title=dict(text=title, x=0.01, xanchor="left") if title else None,
        shapes=shapes(f, style),
        height=height,
        margin=dict(l=10, r=10, t=40 if title else 10, b=10),
        plot_bgcolor="white",
        xaxis=dict(range=[-hx - 0.2, hx + 0.2], visible=False, constrain="domain"),
        yaxis=dict(range=[-hy - 0.2, hy + 0.2], visible=False, scaleanchor="x", scaleratio=1, constrain="domain"),
        showlegend=False,
    )
    return fig
