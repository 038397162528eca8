"""The tournament report of the reference tournament in the real headless Chromium: the standing as the
command printed it, the Elo, head-to-head and score plots, and a working link to every match's report, all
from the folder alone (no network)."""

from __future__ import annotations

import pytest

from ..report.conftest import open_file, plot, report_data, shot  # noqa: F401  (a fixture and helpers)

pytestmark = pytest.mark.slow


def test_the_tournament_report_shows_the_standing_and_links_every_match(reference, open_file):  # noqa: F811
    index = reference["root"] / "report" / "index.html"
    page = open_file(index)
    assert page.network == [] and page.errors == []
    summary = reference["summary"]
    assert report_data(page)["standing"] == summary["standing"]
    for t in summary["standing"]:
        team = t["team"]
        assert page.inner_text(f'[data-key="{team}.points"]') == str(t["points"])
        assert page.inner_text(f'[data-key="{team}.goals"]') == f"{t['goals_for']}:{t['goals_against']}"
        assert page.inner_text(f'[data-key="{team}.elo"]') == f"{t['elo']:.0f}"
    ids = page.evaluate("Array.from(document.querySelectorAll('.js-plotly-plot')).map(d => d.id)")
    assert ids == ["plot-elo", "plot-h2h", "plot-scores"]
    (elo,) = plot(page, "elo")
    assert sorted(elo["y"]) == sorted(t["team"] for t in summary["standing"])
    (h2h,) = plot(page, "h2h")
    assert len(h2h["z"]) == 3 and all(h2h["z"][k][k] is None for k in range(3))
    scores = plot(page, "scores")
    assert len(scores) == 3 and sum(sum(t["y"]) for t in scores) == 6  # every match in one pairing's bars
    links = page.evaluate("Array.from(document.querySelectorAll('a')).map(a => a.getAttribute('href'))")
    match_links = [h for h in links if h.startswith("matches/")]
    assert len(match_links) == 6
    for href in match_links:
        assert (index.parent / href).is_file()
    shot(page, "tournament-report")
    # a match's report, reached by its link, works from the folder and links back
    page.click(f'a[href="{match_links[0]}"]')
    # (the whole page: its figures are drawn while it is parsed, before the data it carries at its end)
    page.wait_for_function(
        "document.readyState === 'complete' && document.querySelectorAll('.js-plotly-plot').length >= 8"
    )
    data = report_data(page)
    row = reference["rows"][data["tournament"]["match_id"]]
    assert data["state_digest"] == row["state_digest"]
    assert page.inner_text("#final-score").replace(" ", "") == f"{row['home_goals']}:{row['away_goals']}"
    assert page.network == [] and page.errors == []
    shot(page, "tournament-match-report")
    page.click("text=← the tournament")
    page.wait_for_selector("#plot-elo")
