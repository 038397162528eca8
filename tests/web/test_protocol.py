"""The page protocol, the tokens and the timeline, without a browser (fast)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simatch.msgs.game_commands import MatchMode
from simatch.web import protocol as P
from simatch.web.access import Access, Grant
from simatch.web.observer import Timeline


def test_commands_are_read_by_name_or_number():
    assert P.parse('{"type": "command", "cmd": "stoprobot"}', "coach").cmd == MatchMode.STOPROBOT
    assert P.parse('{"type": "command", "cmd": 15, "id": 7}', "coach").cmd == MatchMode.STARTROBOT


def test_the_referee_operators_requests_are_read():
    assert P.parse('{"type": "card", "robot": "magenta/4", "card": "yellow"}', "referee").card == "yellow"
    assert P.parse('{"type": "send_off", "robot": "cyan/3", "seconds": 30}', "referee").seconds == 30.0
    assert isinstance(P.parse('{"type": "resume", "id": 3}', "referee"), P.Resume)
    assert P.parse('{"type": "award_goal", "team": "cyan"}', "referee").team == "cyan"


@pytest.mark.parametrize(
    "text, role, why",
    [
        ("{nope", "coach", "not JSON"),
        ("[1, 2]", "coach", "JSON object"),
        ('{"type": "command", "cmd": "WIN"}', "coach", "unknown game command"),
        ('{"type": "command", "cmd": 14}', "coach", "unknown game command number"),
        ('{"type": "command", "cmd": true}', "coach", "name"),
        ('{"type": "command", "cmd": 0, "extra": 1}', "coach", "extra"),
        ('{"type": "limits", "max_vel": NaN, "max_w": 3}', "coach", "max_vel"),
        ('{"type": "limits", "max_vel": 1e9, "max_w": 3}', "coach", "max_vel"),
        ('{"type": "test", "mode": "fly"}', "coach", "mode"),
        ('{"type": "place_ball", "x": 0, "y": 0}', "coach", "may not send"),
        ('{"type": "command", "cmd": 0}', "replay", "may not send"),
        ('{"type": "teleport"}', "referee", "type"),
        ('{"type": "timeline", "action": "rewind"}', "replay", "action"),
        ('"' + "x" * 20000 + '"', "coach", "too long"),
        ('{"type": "card", "robot": "cyan/2", "card": "blue"}', "referee", "card"),
        ('{"type": "card", "robot": "cyan/2", "card": "red"}', "coach", "may not send"),
        ('{"type": "resume"}', "coach", "may not send"),
        ('{"type": "award_goal"}', "referee", "team"),
        ('{"type": "send_off", "robot": "cyan/2", "seconds": -5}', "referee", "seconds"),
    ],
)
def test_malformed_or_forbidden_messages_are_refused_with_a_reason(text, role, why):
    with pytest.raises(P.ProtocolError, match=why):
        P.parse(text, role)


def test_an_unreadable_message_still_gets_its_answer_id():
    assert P.message_id('{"type": "x", "id": 42}') == 42
    assert P.message_id("{broken") is None
    assert P.message_id('{"id": true}') is None


def test_each_page_has_its_own_token():
    access = Access(["cyan", "magenta"])
    tokens = set(access.tokens.values())
    assert len(tokens) == 5 and all(len(t) >= 16 for t in tokens)
    assert access.grant(access.token("coach", "cyan")) == Grant("coach", "cyan")
    assert access.grant(access.token("referee")) == Grant("referee")
    assert access.grant("") is None and access.grant("guess") is None
    urls = access.urls("http://127.0.0.1:1")
    assert urls["magenta coach"] == f"http://127.0.0.1:1/coach/magenta?token={access.token('coach', 'magenta')}"
    assert urls["3d view"] == f"http://127.0.0.1:1/view3d?token={access.token('view3d')}"
    assert set(Access(["cyan"], live=False).tokens) == {Grant("replay"), Grant("view3d")}


def test_timeline_finds_the_sample_at_any_time_across_chunks():
    tl = Timeline(["a", "ball"])
    tl.CHUNK = 8
    for k in range(30):
        tl.append(k * 0.5, np.full((2, 6), k))
    assert tl.count == 30 and tl.start == 0.0 and tl.end == 14.5
    assert tl.index_at(-1.0) == 0
    assert tl.index_at(3.9) == 7 and tl.sample(7)[0, 0] == 7
    assert tl.index_at(4.0) == 8 and tl.index_at(99.0) == 29
    assert json.dumps(float(tl.sample(29)[1, 5])) == "29.0"


def test_timeline_keeps_a_bounded_history_and_reads_what_it_let_go_as_the_oldest_kept():
    tl = Timeline(["a"], keep=10.0)
    tl.CHUNK = 8
    for k in range(80):  # 40 s at 2 samples a second: ten chunks of 4 s
        tl.append(k * 0.5, np.full((1, 6), k))
    assert tl.count == 80 and tl.end == 39.5
    assert 10.0 <= tl.end - tl.start <= 10.0 + 2 * 4.0, "the last `keep` seconds, give or take two chunks"
    first = tl.first
    assert first % 8 == 0 and tl.time(first) == tl.start and tl.sample(first)[0, 0] == first
    assert tl.index_at(0.0) == first and tl.sample(0)[0, 0] == first, "what was let go reads as the oldest kept"
    assert tl.index_at(35.2) == 70 and tl.sample(70)[0, 0] == 70
    assert tl.nbytes == (80 - first) // 8 * 8 * (8 + 6 * 4)
    whole = Timeline(["a"])
    assert whole.keep == Timeline.KEEP >= 1810.0, "a whole match (two halves and the break) by default"
