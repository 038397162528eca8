"""`simatch replay FILE --info`: what a recording holds, with a message count for every channel."""

from __future__ import annotations

import json
import subprocess
import sys

from mcap.reader import make_reader

from simatch.record.layout import bus_topic


def _info(path, *extra):
    return subprocess.run(
        [sys.executable, "-m", "simatch", "replay", str(path), "--info", *extra],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    ).stdout


def test_info_counts_the_messages_of_every_channel_the_3d_scene_included(recording):
    path, _ = recording
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    # the counts in the file's own summary, by the names simatch gives the channels (its clock is /simatch/clock in
    # the file, ROS 2's standard /clock beside it is ros/clock)
    truth = {}
    for cid, n in summary.statistics.channel_message_counts.items():
        channel = summary.channels[cid]
        truth[bus_topic(channel.topic, summary.schemas[channel.schema_id].name)] = n
    assert truth["clock"] == truth["ros/clock"] > 10
    assert truth["scene/field"] == 1 and truth["scene/game"] > 10
    info = json.loads(_info(path, "--json"))
    assert info["messages"] == truth
    assert set(info["messages"]) == set(info["topics"])
    lines = {line.split()[0]: line.split() for line in _info(path).splitlines() if line.startswith("  ")}
    for topic in ("scene/field", "scene/game", "model_states"):
        assert lines[topic][-1] == str(truth[topic]), lines[topic]
