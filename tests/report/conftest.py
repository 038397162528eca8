"""Match reports of a real recorded match, opened in Debian's headless Chromium (the web UI tests' browser).

The match (``msl_5v5``, nubot against simple, two halves of 30 s) is played once per session by
``simatch run --record --report``; its recording is reported again by ``simatch report`` and exported by
``simatch export``, whose tables are the independent account the reports' numbers are checked against.
Screenshots go to test-artifacts/report/.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts" / "report"
MATCH = [
    "--seed",
    "3",
    "--set",
    "match.half_duration=30",
    "--set",
    "match.half_time=2",
    "--set",
    "teams.magenta.strategy=simple",
]


def simatch(*args: str, timeout: float = 900) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "simatch", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=dict(os.environ, PYTHONPATH=str(REPO / "examples")),
    )


@pytest.fixture(scope="session")
def recorded(tmp_path_factory):
    """The match: its run's JSON, the recording, the report written live, the one written from the recording,
    and the exported tables (name -> list of rows)."""
    root = tmp_path_factory.mktemp("match")
    mcap, live, again = root / "match.mcap", root / "live.html", root / "recorded.html"
    run = simatch("run", "msl_5v5", *MATCH, "--json", "--quiet", "--record", str(mcap), "--report", str(live))
    assert run.returncode == 0, run.stderr
    rep = simatch("report", str(mcap), "-o", str(again))
    assert rep.returncode == 0, rep.stderr
    exp = simatch("export", str(mcap), "--out", str(root / "tables"))
    assert exp.returncode == 0, exp.stderr
    tables = {p.stem: pq.read_table(p).to_pylist() for p in (root / "tables").glob("*.parquet")}
    return {
        "run": json.loads(run.stdout),
        "mcap": mcap,
        "live": live,
        "recorded": again,
        "tables": tables,
        "root": root,
    }


@pytest.fixture
def open_file(browser):
    """``open_file(path)``: the page in a fresh context that refuses (and counts) every request off this disk."""
    made = []

    def make(path: Path, width: int = 1400, height: int = 900):
        context = browser.new_context(viewport={"width": width, "height": height})
        page = context.new_page()
        page.network = []
        page.errors = []
        page.on("pageerror", lambda exc: page.errors.append(str(exc)))

        def route(r):
            if r.request.url.startswith("file://"):
                r.continue_()
            else:
                page.network.append(r.request.url)
                r.abort()

        context.route("**/*", route)
        page.goto(path.resolve().as_uri())
        page.wait_for_function(
            "document.querySelectorAll('.js-plotly-plot').length > 0 && "
            "Array.from(document.querySelectorAll('.js-plotly-plot')).every(d => d._fullLayout)"
        )
        made.append(context)
        return page

    yield make
    for context in made:
        context.close()


def shot(page, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    return path


def report_data(page) -> dict:
    return page.evaluate("JSON.parse(document.getElementById('report-data').textContent)")


def plot(page, name: str) -> list[dict]:
    """The traces of plot ``name`` as Plotly holds them in the page."""
    return page.evaluate(
        "id => { const d = document.getElementById('plot-' + id); return d.data.map(t => ({type: t.type, "
        "name: t.name, x: Array.from(t.x || []), y: Array.from(t.y || []), z: t.z ? t.z.map(r => Array.from(r)) : null,"
        " text: t.text ? Array.from(t.text) : null, meta: t.meta || null})); }",
        name,
    )
