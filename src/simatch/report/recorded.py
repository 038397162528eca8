"""The match analysis of a recording (``simatch report FILE.mcap``): the same numbers as the live analysis of
the run that was recorded (`simatch.report.live`), read back from its messages.

A recording cut short or damaged is analysed as far as it is intact; what was wrong is in ``problems``.
"""

from __future__ import annotations

import json

from ..bus import topics
from ..record.reader import Recording
from .analysis import MatchAnalysis, MatchMeta

_WANTED = (topics.MODEL_STATES, topics.BALL_CONTACTS, topics.EVENTS, topics.GAME_STATE)


def analyse_recording(path, labels: dict[str, str] | None = None) -> tuple[dict, Recording]:
    """The analysis of the recording at ``path`` (`MatchAnalysis.finish`) and the opened recording."""
    rec = Recording(path)
    scene = rec.scene()
    seed = int(rec.metadata.get("seed", 0))
    analysis = MatchAnalysis(MatchMeta.of_scene(scene, seed, labels))
    last_result = ""
    wanted = [t for t in rec.topics() if t in _WANTED or t.endswith("/" + topics.STRATEGY_INFO)]
    for topic, _, m in rec.messages(topics=wanted):
        if topic == topics.MODEL_STATES:
            n = len(m.name)
            analysis.states(int(m.step), list(m.name), m.pose.reshape(n, 7), m.twist.reshape(n, 6))
        elif topic == topics.BALL_CONTACTS:
            analysis.contacts(m.stamp, m.step, m.touching, m.holder, m.kicker, m.kick_speed, m.lob)
        elif topic == topics.EVENTS:
            analysis.event(m)
        elif topic == topics.GAME_STATE:
            analysis.game_state_message(m)
            last_result = m.result
        else:
            analysis.strategy(m.stamp, topic.rsplit("/", 1)[0], m.role)
    end = rec.end or {}
    extra = {
        "state_digest": end.get("state_digest"),
        "sim_seconds": float(end["sim_seconds"]) if end.get("sim_seconds") else None,
        "recording": {"path": str(rec.path), "status": end.get("status", "not finalised"), "problems": rec.problems},
    }
    if last_result:  # the run's result as the referee last published it
        try:
            extra["result"] = json.loads(last_result)
        except ValueError:
            pass
    return analysis.finish(extra), rec
