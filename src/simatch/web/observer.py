"""What the web UI knows about a run, gathered from the bus only (never from the simulator's insides).

`RunObserver` subscribes to the run's topics (model_states, each robot's OmniVisionInfo and
StrategyInfo, each team's CoachInfo, game_state, events) and keeps, with their simulated time stamps:

* a `Timeline` of the exact world (every model's x, y, z, yaw, vx, vy) sampled at about 66 Hz of
  simulated time, for the last hour of the run (`Timeline.KEEP`: a whole match): live pages draw from it, the
  replay page and the 3D view look back through it;
* the last second of every robot's perception and intentions, for the coach pages;
* every event and every change of the game state, and the cards each robot was shown.

Bus callbacks run in the simulation's thread and only append; the server's thread reads. Appends of
whole objects and reads of filled slots need no lock, so the simulation never waits for a viewer.
"""

from __future__ import annotations

import bisect
import json
import math
from collections import deque
from typing import Any

import numpy as np

from .. import msgs
from ..bus import Bus, topics
from ..msgs.game_commands import name as command_name

#: columns of a Timeline sample, per model
COLUMNS = ("x", "y", "z", "yaw", "vx", "vy")


class Timeline:
    """Samples of every model's state, appended in time order, stored in fixed-size chunks so that a long
    match costs a few tens of megabytes and no copying (float32: a display, not a digest).

    The history is bounded: once it spans more than ``keep`` seconds, its oldest chunk is let go (about a
    minute of samples at a time), so a run that goes on for hours holds the last ``keep`` seconds at most.
    Indices stay absolute (``count`` keeps counting); one that has been let go reads as the oldest kept.
    The chunks are one tuple replaced whole, so a reader in another thread never sees half a change."""

    CHUNK = 4096
    KEEP = 3600.0  # [s] of simulated time kept by default: a whole match (2 x 15 min and the break) and more

    def __init__(self, names: list[str], keep: float | None = None):
        self.names = list(names)
        self.keep = self.KEEP if keep is None else keep
        # (chunks let go, times, samples, each chunk's first time)
        self._chunks: tuple[int, list[np.ndarray], list[np.ndarray], list[float]] = (0, [], [], [])
        self.count = 0

    def append(self, t: float, sample: np.ndarray) -> None:
        k, j = divmod(self.count, self.CHUNK)
        dropped, times, data, starts = self._chunks
        if k - dropped == len(times):
            times = times + [np.empty(self.CHUNK)]
            data = data + [np.empty((self.CHUNK, len(self.names), len(COLUMNS)), dtype=np.float32)]
            starts = starts + [t]
            if len(starts) > 2 and t - starts[1] > self.keep:  # the second chunk alone still spans `keep`
                dropped, times, data, starts = dropped + 1, times[1:], data[1:], starts[1:]
            self._chunks = (dropped, times, data, starts)
        times[k - dropped][j] = t
        data[k - dropped][j] = sample
        self.count += 1  # last: a reader never sees a slot before it is filled

    @property
    def first(self) -> int:
        """The index of the oldest sample kept."""
        return self._chunks[0] * self.CHUNK

    @property
    def start(self) -> float:
        return self.time(self.first) if self.count else 0.0

    @property
    def end(self) -> float:
        return self.time(self.count - 1) if self.count else 0.0

    def _slot(self, i: int):
        dropped, times, data, _ = self._chunks
        k, j = divmod(max(i, dropped * self.CHUNK), self.CHUNK)
        return times[k - dropped], data[k - dropped], j

    def time(self, i: int) -> float:
        times, _, j = self._slot(i)
        return float(times[j])

    def sample(self, i: int) -> np.ndarray:
        _, data, j = self._slot(i)
        return data[j]

    def index_at(self, t: float) -> int:
        """The last sample at or before ``t`` (the oldest kept if ``t`` is earlier); -1 if there is none."""
        n = self.count
        if n == 0:
            return -1
        dropped, times, _, starts = self._chunks
        last = (n - 1) // self.CHUNK - dropped
        k = min(max(0, bisect.bisect_right(starts, t) - 1), last)
        filled = min(self.CHUNK, n - (k + dropped) * self.CHUNK)
        j = int(np.searchsorted(times[k][:filled], t, side="right")) - 1
        return (k + dropped) * self.CHUNK + max(j, 0)

    @property
    def nbytes(self) -> int:
        """The memory the samples hold now [bytes]."""
        _, times, data, _ = self._chunks
        return sum(a.nbytes for a in times) + sum(a.nbytes for a in data)


def _stamped_before(buffer: deque, t: float):
    """The newest (stamp, message) entry of ``buffer`` not after ``t`` (else the oldest), or None."""
    entries = tuple(buffer)  # one C call: atomic under the GIL while the simulation appends
    for entry in reversed(entries):
        if entry[0] <= t + 1e-9:
            return entry[1]
    return entries[0][1] if entries else None


def event_record(ev) -> dict:
    """A GameEvent as the pages show it (world frame); JSON in ``detail`` is unpacked into ``info``."""
    out: dict[str, Any] = {"t": round(float(ev.stamp), 3), "type": ev.type}
    if ev.team:
        out["team"] = ev.team
    if ev.robot:
        out["robot"] = int(ev.robot)
    if ev.x or ev.y:
        out["x"], out["y"] = round(float(ev.x), 3), round(float(ev.y), 3)
    if ev.value or ev.limit:
        out["value"], out["limit"] = round(float(ev.value), 4), round(float(ev.limit), 4)
    detail = ev.detail or ""
    if detail.startswith("{"):
        try:
            out["info"] = json.loads(detail)
        except ValueError:
            out["detail"] = detail
    elif detail:
        out["detail"] = detail
    return out


def game_record(msg) -> dict:
    """A GameState as a plain dict (world frame)."""
    teams = list(msg.teams)

    def per_team(values) -> dict:
        return {team: int(v) for team, v in zip(teams, values)}

    return {
        "t": round(float(msg.stamp), 3),
        "stage": msg.stage,
        "phase": msg.phase,
        "paused": bool(msg.paused),
        "reason": msg.reason,
        "clock": round(float(msg.clock), 2),
        "stage_time_left": round(float(msg.stage_time_left), 2),
        "command": int(msg.command),
        "next_command": int(msg.next_command),
        "command_name": command_name(msg.command),
        "next_command_name": command_name(msg.next_command),
        "command_team": msg.command_team,
        "teams": teams,
        "score": per_team(msg.score),
        "yellow_cards": per_team(msg.yellow_cards),
        "red_cards": per_team(msg.red_cards),
        "fouls": per_team(msg.fouls),
        "sent_off": list(msg.sent_off),
        "last_touch": msg.last_touch,
        "ball_in_play": bool(msg.ball_in_play),
        "manual": bool(msg.manual),
        "ball_x": round(float(msg.ball_x), 3),
        "ball_y": round(float(msg.ball_y), 3),
        # the way each team attacks now (the teams change ends at half time); empty from judges without sides
        "attacks": {team: side for team, side in zip(teams, msg.attacks)},
    }


class RunObserver:
    """Subscribes to a run's topics on ``bus`` and keeps what the pages draw (see the module docstring);
    ``keep`` bounds the Timeline's history (seconds)."""

    SAMPLE_PERIOD = 1.0 / 66.0  # [s] of simulated time between Timeline samples
    RECENT = 1.0  # [s] of perception and intentions kept per robot

    def __init__(self, bus: Bus, robots: dict[str, list[int]], control_period: float, keep: float | None = None):
        self.bus = bus
        self.keep = keep  # [s] of the Timeline's history (None: Timeline.KEEP)
        self.robots = robots
        self.timeline: Timeline | None = None
        self.events: list[dict] = []
        self.games: list[tuple[float, dict]] = []
        self.cards: dict[str, list[int]] = {}  # robot -> [yellow, red] cards shown so far
        keep = max(4, int(math.ceil(self.RECENT / control_period)) + 1)
        self.vision: dict[tuple[str, int], deque] = {}
        self.intent: dict[tuple[str, int], deque] = {}
        self.coach: dict[str, Any] = {}
        self.latest_time = 0.0
        self._next_sample = -math.inf
        self._subs = [
            bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, self._on_states),
            bus.subscribe(topics.EVENTS, msgs.GameEvent, self._on_event),
            bus.subscribe(topics.GAME_STATE, msgs.GameState, self._on_game),
        ]
        for team, ids in robots.items():
            self._subs.append(
                bus.subscribe(
                    topics.team_topic(team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, self._coach_callback(team)
                )
            )
            for rid in ids:
                self.vision[(team, rid)] = v = deque(maxlen=keep)
                self.intent[(team, rid)] = s = deque(maxlen=keep)
                self._subs.append(
                    bus.subscribe(
                        topics.robot_topic(team, rid, topics.OMNI_VISION), msgs.OmniVisionInfo, self._stamped(v)
                    )
                )
                self._subs.append(
                    bus.subscribe(
                        topics.robot_topic(team, rid, topics.STRATEGY_INFO), msgs.StrategyInfo, self._stamped(s)
                    )
                )

    # --- bus callbacks (the simulation's thread) ----------------------------------------------------------
    def _on_states(self, msg) -> None:
        t = float(msg.stamp)
        self.latest_time = t
        if t < self._next_sample:
            return
        self._next_sample = t + self.SAMPLE_PERIOD - 1e-9
        self.add_states(msg)

    def add_states(self, msg) -> None:
        """Append a ModelStates sample whatever the sampling rate (e.g. a recording's very last one)."""
        t = float(msg.stamp)
        if self.timeline is None:
            self.timeline = Timeline(list(msg.name), keep=self.keep)
        m = len(msg.name)
        pose = np.asarray(msg.pose).reshape(m, 7)
        twist = np.asarray(msg.twist).reshape(m, 6)
        sample = np.empty((m, len(COLUMNS)))
        sample[:, 0:3] = pose[:, 0:3]
        sample[:, 3] = 2.0 * np.arctan2(pose[:, 6], pose[:, 3])
        sample[:, 4:6] = twist[:, 0:2]
        self.timeline.append(t, sample)

    def _on_event(self, ev) -> None:
        self.events.append(event_record(ev))
        if ev.type in ("yellow_card", "red_card") and ev.team:
            counts = self.cards.setdefault(f"{ev.team}/{int(ev.robot)}", [0, 0])
            counts[ev.type == "red_card"] += 1

    def _on_game(self, msg) -> None:
        self.games.append((float(msg.stamp), game_record(msg)))

    def _coach_callback(self, team: str):
        def on_coach(msg) -> None:
            self.coach[team] = msg

        return on_coach

    @staticmethod
    def _stamped(buffer: deque):
        def on_msg(msg) -> None:
            buffer.append((float(msg.stamp), msg))

        return on_msg

    # --- reading (the server's thread) -----------------------------------------------------------------------
    def game_at(self, t: float) -> dict | None:
        games = self.games
        i = bisect.bisect_right(games, t + 1e-9, key=lambda g: g[0]) - 1
        return games[i][1] if i >= 0 else None

    def vision_at(self, team: str, rid: int, t: float):
        return _stamped_before(self.vision[(team, rid)], t)

    def intent_at(self, team: str, rid: int, t: float):
        return _stamped_before(self.intent[(team, rid)], t)

    def close(self) -> None:
        for sub in self._subs:
            sub.close()
        self._subs.clear()
