"""A league and a knockout played for real (short matches, one after another in this process: the formats'
logic, not Ray's, is under test here), with their reports."""

from __future__ import annotations

import pytest

from simatch.tournament import PlainLoop, Tournament, parse_entries

from ..report.conftest import open_file, plot  # noqa: F401  (a fixture and a helper)

pytestmark = pytest.mark.slow

SHORT = {"match.half_duration": 5, "match.half_time": 1}


def test_a_league_in_matchdays_with_the_table_after_each(tmp_path, open_file):  # noqa: F811
    entries = parse_entries(["nubot,simple,startpose"])
    t = Tournament(
        entries, seeds=[0], out=tmp_path / "out", overrides=SHORT, format="league", report=tmp_path / "report"
    )
    summary = t.play(PlainLoop())
    assert summary["complete"] and summary["matches"]["played"] == 6
    prog = summary["progression"]
    assert prog["matchdays"] == ["matchday 1", "matchday 2", "matchday 3"]
    final = {t_["team"]: t_["rank"] for t_ in summary["standing"]}
    assert {team: places[-1] for team, places in prog["places"].items()} == final
    # each team rests on one matchday of three: two matchdays with a match each way
    stages = {}
    for m in t.format.matches:
        stages.setdefault(m.stage, set()).update({m.home, m.away})
    assert all(len(teams) == 2 for teams in stages.values())
    page = open_file(tmp_path / "report" / "index.html")
    traces = plot(page, "progression")
    assert {tr["name"] for tr in traces} == {"nubot", "simple", "startpose"}
    assert all(tr["y"] == prog["places"][tr["name"]] for tr in traces)


def test_a_knockout_plays_round_after_round_and_crowns_a_champion(tmp_path, open_file):  # noqa: F811
    # startpose robots walk to their start poses and stand: nubot scores against them, so no decider is needed
    entries = parse_entries(["nubot,simple,startpose"])
    overrides = {"match.half_duration": 15, "match.half_time": 1}
    t = Tournament(
        entries, seeds=[0], out=tmp_path / "out", overrides=overrides, format="knockout", report=tmp_path / "report"
    )
    summary = t.play(PlainLoop())
    rounds = summary["format_detail"]["rounds"]
    assert [r[0]["round"] for r in rounds] == ["semi-final", "final"]
    semis = {(tie["a"], tie["b"]): tie for tie in rounds[0]}
    assert semis[("nubot", None)]["how"] == "bye"
    assert ("simple", "startpose") in semis
    final = rounds[1][0]
    assert final["a"] == "nubot" and final["winner"] and final["how"]
    assert summary["format_detail"]["champion"] == final["winner"]
    assert summary["complete"]
    page = open_file(tmp_path / "report" / "index.html")
    assert f"champion: {final['winner']}" in page.inner_text("body")
    assert page.locator("#bracket table").count() == 2
