"""One HTML page of figures, tables and the numbers behind them, that opens with no network.

Plotly's own JavaScript is either inlined (a single self-contained file: a match report) or a file beside the
pages (a tournament's folder, where dozens of match reports share one copy: ``plotly.min.js``). The page
carries the data it was made from as JSON (``<script type="application/json" id="report-data">``) for
scripts and tests that want the numbers rather than the pictures.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import plotly
import plotly.graph_objects as go
import plotly.offline

from .files import write_atomic

PLOTLY_FILE = "plotly.min.js"

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0; background: #f4f5f7;
       color: #1f2328; }
header { background: #1f2d3d; color: #fff; padding: 18px 28px; }
header h1 { margin: 0 0 4px 0; font-size: 26px; font-weight: 600; }
header .sub { color: #c9d3df; font-size: 14px; }
main { padding: 8px 28px 40px 28px; max-width: 1400px; }
section { background: #fff; border-radius: 8px; box-shadow: 0 1px 3px rgba(0,0,0,.08); margin: 18px 0;
          padding: 14px 18px; }
section h2 { margin: 0 0 8px 0; font-size: 18px; font-weight: 600; }
section p.note { color: #57606a; font-size: 13px; margin: 2px 0 8px 0; }
.grid2 { display: grid; grid-template-columns: 1fr 1fr; gap: 12px; }
.grid3 { display: grid; grid-template-columns: 1fr 1fr 1fr; gap: 12px; }
@media (max-width: 1100px) { .grid2, .grid3 { grid-template-columns: 1fr; } }
table { border-collapse: collapse; font-size: 14px; }
th, td { padding: 5px 10px; border-bottom: 1px solid #e5e7eb; text-align: right; white-space: nowrap; }
th { background: #f6f8fa; font-weight: 600; }
td.l, th.l { text-align: left; }
td.wrap { white-space: normal; text-align: left; max-width: 760px; }
span.wrap { white-space: normal; text-align: left; display: block; min-width: 320px; max-width: 640px; }
.score { font-size: 40px; font-weight: 700; letter-spacing: 2px; }
.swatch { display: inline-block; width: 12px; height: 12px; border-radius: 3px; margin-right: 6px;
          vertical-align: -1px; }
.failed { color: #b42318; }
details summary { cursor: pointer; color: #0969da; margin: 6px 0; }
a { color: #0969da; }
"""


class Page:
    """Sections of HTML (figures, tables, text) in order, written as one file."""

    def __init__(self, title: str, subtitle: str = "", heading_html: str = ""):
        self.title = title
        self.subtitle = subtitle
        self.heading_html = heading_html
        self.parts: list[str] = []
        self.figures = 0

    def figure(self, fig: go.Figure, name: str) -> str:
        """A figure's div (with id ``plot-<name>``), to place inside a section."""
        self.figures += 1
        return fig.to_html(
            full_html=False,
            include_plotlyjs=False,
            div_id=f"plot-{name}",
            config={"displaylogo": False, "responsive": True},
        )

    def section(self, title: str, body: str, note: str = "", anchor: str = "") -> None:
        ident = f' id="{html.escape(anchor)}"' if anchor else ""
        text = f'<p class="note">{html.escape(note)}</p>' if note else ""
        self.parts.append(f"<section{ident}><h2>{html.escape(title)}</h2>{text}{body}</section>")

    def render(self, data: dict | None = None, plotly_js: str = "inline") -> str:
        """The page; ``plotly_js``: "inline" (self-contained) or a path relative to the page."""
        if plotly_js == "inline":
            script = f"<script>{plotly.offline.get_plotlyjs()}</script>"
        else:
            script = f'<script src="{html.escape(plotly_js)}"></script>'
        payload = ""
        if data is not None:
            text = json.dumps(data, separators=(",", ":"), allow_nan=False, default=_plain).replace("</", "<\\/")
            payload = f'<script type="application/json" id="report-data">{text}</script>'
        sub = f'<div class="sub">{html.escape(self.subtitle)}</div>' if self.subtitle else ""
        return (
            "<!DOCTYPE html>\n"
            f'<html lang="en"><head><meta charset="utf-8"><title>{html.escape(self.title)}</title>'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<style>{STYLE}</style>{script}</head><body>"
            f"<header><h1>{html.escape(self.title)}</h1>{sub}{self.heading_html}</header>"
            f"<main>{''.join(self.parts)}</main>{payload}</body></html>\n"
        )

    def write(self, path: str | Path, data: dict | None = None, plotly_js: str = "inline") -> Path:
        """Write the page at ``path`` (atomically: a reader never sees half a page)."""
        path = Path(path)
        write_atomic(path, self.render(data, plotly_js))
        return path


def table(
    header: list[str], rows: list[list], left: int = 1, keys: list[list[str]] | None = None, css: str = ""
) -> str:
    """An HTML table; the first ``left`` columns align left; ``keys`` give cells a ``data-key``."""
    head = "".join(f'<th class="{"l" if i < left else ""}">{html.escape(str(h))}</th>' for i, h in enumerate(header))
    body = []
    for r, row in enumerate(rows):
        cells = []
        for i, cell in enumerate(row):
            cls = "l" if i < left else ""
            key = keys[r][i] if keys and r < len(keys) and i < len(keys[r]) and keys[r][i] else ""
            attr = f' data-key="{html.escape(key)}"' if key else ""
            cells.append(f'<td class="{cls}"{attr}>{cell if isinstance(cell, Raw) else html.escape(_fmt(cell))}</td>')
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f'<table class="{css}"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'


class Raw(str):
    """HTML that a table cell takes as it is (a link, a swatch)."""


def swatch(colour: str, text: str) -> Raw:
    return Raw(f'<span class="swatch" style="background:{html.escape(colour)}"></span>{html.escape(text)}')


def link(href: str, text: str) -> Raw:
    return Raw(f'<a href="{html.escape(href)}">{html.escape(text)}</a>')


def _fmt(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.2f}" if abs(value) < 100 else f"{value:.1f}"
    return str(value)


def _plain(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def write_plotly_js(folder: Path) -> Path:
    """Plotly's JavaScript beside the pages of a folder (written once)."""
    path = folder / PLOTLY_FILE
    if not path.exists():
        write_atomic(path, plotly.offline.get_plotlyjs())
    return path
