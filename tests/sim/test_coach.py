"""Without a referee each team has a coach that commands its own team only, mirrored per team."""

from __future__ import annotations

from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import MatchMode, for_team, mirror


def test_commands_are_mirrored_per_team():
    assert mirror(MatchMode.OUR_KICKOFF) == MatchMode.OPP_KICKOFF
    assert mirror(MatchMode.OPP_CORNERKICK) == MatchMode.OUR_CORNERKICK
    for neutral in (MatchMode.STOPROBOT, MatchMode.STARTROBOT, MatchMode.DROPBALL, MatchMode.PARKINGROBOT):
        assert mirror(neutral) == neutral
    assert for_team(MatchMode.OUR_FREEKICK, "cyan", "magenta") == MatchMode.OPP_FREEKICK
    assert for_team(MatchMode.OUR_FREEKICK, "cyan", "cyan") == MatchMode.OUR_FREEKICK


def test_a_coach_commands_its_own_team_only(field_sim):
    sim = field_sim()
    heard = {"cyan": [], "magenta": []}
    for team in heard:
        sim.bus.subscribe(topics.team_topic(team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, heard[team].append)
    sim.step()
    assert heard["cyan"][-1].match_mode == MatchMode.STOPROBOT
    sim.coaches["cyan"].send(MatchMode.OUR_KICKOFF)
    sim.run(seconds=0.05)
    c = heard["cyan"][-1]
    assert (c.match_mode, c.match_type) == (MatchMode.OUR_KICKOFF, MatchMode.OUR_KICKOFF)
    assert heard["magenta"][-1].match_mode == MatchMode.STOPROBOT
    sim.coaches["cyan"].start_play()
    sim.run(seconds=0.05)
    c = heard["cyan"][-1]
    assert (c.match_mode, c.match_type) == (MatchMode.STARTROBOT, MatchMode.OUR_KICKOFF)  # type keeps the set piece
    assert any(e["type"] == "coach_command" and e["team"] == "cyan" for e in sim.events)
