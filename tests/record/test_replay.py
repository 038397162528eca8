"""Playback publishes every recorded message again, equal to the recorded one, in order."""

from __future__ import annotations

from simatch import msgs
from simatch.record import Player, Recording, layout

#: channels that are no bus topics: the 3D scene, and ROS 2's /clock
NOT_BUS = ("scene/", layout.ROS_ONLY)


def test_every_replayed_message_equals_the_recorded_one(recording):
    path, _ = recording
    rec = Recording(path)
    recorded = [(topic, data) for topic, _, data in rec.raw() if not topic.startswith(NOT_BUS)]
    player = Player(path, pace=None)
    encode = msgs.encode
    seen = []
    sub = player.bus.subscribe_all("**", lambda topic, msg: seen.append((topic, encode(msg))))
    try:
        assert player.play() == len(recorded)
    finally:
        sub.close()
    assert seen == recorded
    assert player.done and player.time == rec.end_ns / 1e9


def test_from_a_time_with_the_latest_state_of_every_topic_first(recording):
    path, _ = recording
    rec = Recording(path)
    player = Player(path, pace=None, start=1.0)
    seen = []
    player.bus.subscribe_all("**", lambda topic, msg: seen.append((topic, msg)))
    player.play()
    topics = rec.topics()
    first = {}
    for topic, msg in seen:
        first.setdefault(topic, msg)
    # the coach command in force at 1 s reaches a late viewer even though it was given at 0 s
    assert first["cyan/receive_from_coach"].match_mode == 15
    assert first["operator"].call == "apply_wrench"  # the latest operator command before 1 s
    assert set(first) == {t for t in topics if not t.startswith(NOT_BUS)}
    states = [m for t, m in seen if t == "model_states"]
    assert states[0].step == 199 and states[1].step == 200 and states[-1].step == 399


def test_player_offers_what_a_viewer_needs(recording):
    path, _ = recording
    player = Player(path, pace=2.0)
    assert player.scene.name == "msl_5v5" and player.scene.spec.world.length == 22.0
    assert player.duration == 1.995 and player.bus.run == "embedded"


def test_a_viewer_attaches_to_the_replay_through_the_extension_hook(recording, monkeypatch, capsys):
    from simatch import cli
    from simatch.cli import replay

    from . import viewer_hook

    path, _ = recording
    monkeypatch.setattr(replay, "EXTENSIONS", ["tests.record.viewer_hook:CountingViewer"])
    assert cli.main(["replay", str(path), "--speed", "max", "--count", "--quiet"]) == 0
    seen = viewer_hook.SEEN
    assert seen["scene"] == "msl_5v5" and seen["done"] and seen["model_states"] == 400
    assert "replayed" in capsys.readouterr().out
