"""Referee scenarios: one small TOML file per rule case, run through the Python API.

A scenario places robots and the ball on the msl_5v5 field, starts the referee in a given situation (the
operator's force start, a restart, or the match's own kick-off), scripts robots (body-frame velocities,
dribbler, kicks), the ball and operator requests at given times, and states what must happen (events with
their fields and measured values, commands each team hears, the final score) and what must not (no foul
at all in a legal case). Format (all times in seconds after the setup)::

    rule = "dribbling"                 # the rule under test (docs/referee.md)
    legal = false                      # a legal case must produce no foul of any rule
    description = "..."
    duration = 6.0
    [settings]                         # scene overrides, e.g. "judge.stop_time" = 0.5
    [setup]
    stage = "second_half"              # optional: play the match (robots off the field) until this stage
                                       # begins, then set up (the teams have changed ends by then)
    start = "play"                     # "play" (force start) | "match" (the referee's own kick-off) |
                                       # { command = "OUR_FREEKICK", team = "cyan", spot = [x, y] }
    ball = [x, y]                      # or { x = .., y = .., vx = .., vy = .., vz = .. }
    [setup.robots]                     # world frame [x, y, yaw]; robots not listed stand off the field
    "cyan/2" = [-1.0, 0.0, 0.0]
    [[script]]
    at = 0.5
    robot = "cyan/2"                   # vel = [vx, vy, w] (body frame, kept), dribble = true, kick = 5.0, lob
    [[script]]
    at = 1.0
    ball = { x = 0.0, vx = 3.0 }       # or operator = { op = "pause" } / { op = "command", command = ..., team = .. }
    [[expect]]                         # an event: every given field must match (a number 0 matches a field the
                                       # event leaves out); value_min/value_max/within/detail_has
    type = "dribble_too_far"
    team = "cyan"
    robot = 2
    [[expect]]
    heard = "OUR_FREEKICK"             # a command (MatchMode name) that `team` heard
    team = "magenta"
    [absent]
    types = ["goal"]                   # event types that must not occur
    [final]
    score = { cyan = 0, magenta = 0 }  # and/or phase, stage, fouls, sent_off, yellow_cards, red_cards
    [[at_end]]                         # where a model is at the end (proves the case did what it says)
    model = "cyan/4"
    x_min = 0.5                        # x_min, x_max, y_min, y_max
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import MatchMode
from simatch.scene.referee.log import FOUL_TYPES

SCENARIOS = Path(__file__).parent / "scenarios"
ROBOTS = [f"{t}/{i}" for t in ("cyan", "magenta") for i in range(1, 6)]


def parked(name: str) -> tuple[float, float, float]:
    """Where a robot that the scenario does not use stands: off the field, beside the side line at
    y = -7.9, cyan in its own half and magenta in its own."""
    team, rid = name.split("/")
    side = -1 if team == "cyan" else 1
    return (side * (5.5 + 0.8 * (int(rid) - 1)), -7.9, 0.0)


@dataclass
class Outcome:
    events: list[dict]
    heard: dict[str, list[tuple[float, int]]]
    game: dict
    result: dict
    t0: float
    positions: dict[str, tuple[float, float]]
    sim: Any = None

    def of_type(self, *types: str) -> list[dict]:
        return [e for e in self.events if e["type"] in types]

    def describe(self) -> str:
        lines = [
            f"  {e['t']:8.3f} {e['type']:22s} {e.get('team', ''):8s} {e.get('robot', '')!s:3s} "
            f"{e.get('value', '')!s:>8.8s} / {e.get('limit', '')!s:8.8s} {e.get('detail', '')}"
            for e in self.events
        ]
        heard = {t: [(round(s, 3), MatchMode(c).name) for s, c in h] for t, h in self.heard.items()}
        return "\n".join(["events (t after setup):", *lines, f"heard: {heard}", f"game: {self.game}"])


@dataclass
class Scenario:
    path: Path
    data: dict = field(repr=False)

    @classmethod
    def load(cls, path: Path) -> Scenario:
        return cls(path, tomllib.loads(path.read_text()))

    @property
    def name(self) -> str:
        return self.path.stem

    @property
    def rule(self) -> str:
        return self.data["rule"]

    @property
    def legal(self) -> bool:
        return bool(self.data["legal"])

    # --- running --------------------------------------------------------------------------------------
    def run(self, seed: int = 0, keep: bool = False) -> Outcome:
        d = self.data
        overrides = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": "msl_referee"}
        overrides.update(d.get("settings", {}))
        sim = simatch.Simulation("msl_5v5", seed=seed, overrides=overrides)
        try:
            return self._run(sim, keep)
        finally:
            if not keep:
                sim.close()

    def _run(self, sim, keep: bool) -> Outcome:
        d = self.data
        setup = d.get("setup", {})
        heard: dict[str, list[tuple[float, int]]] = {"cyan": [], "magenta": []}
        for team, log in heard.items():

            def on_coach(msg, log=log):
                if not log or log[-1][1] != msg.match_mode:
                    log.append((sim.time, int(msg.match_mode)))

            sim.bus.subscribe(topics.team_topic(team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, on_coach)
        sim.step()  # the referee begins: STOP
        placed = {k: v for k, v in setup.get("robots", {}).items()}
        stage = setup.get("stage")
        for name in ROBOTS:
            x, y, yaw = parked(name) if stage is not None else placed.get(name, parked(name))
            sim.set_model_state(name, x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)
            sim.take_control(name)
        if stage is not None:
            self._until_stage(sim, stage)
            for name in ROBOTS:  # the referee placed them for the new ends: where the scenario wants them
                x, y, yaw = placed.get(name, parked(name))
                sim.set_model_state(name, x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)
        ball = setup.get("ball", [0.0, 0.0])
        state = {"z": 0.11, "vx": 0.0, "vy": 0.0, "vz": 0.0, "wx": 0.0, "wy": 0.0, "wz": 0.0}
        state.update(ball if isinstance(ball, dict) else {"x": ball[0], "y": ball[1]})
        sim.set_model_state("ball", **state)
        sim.step()
        referee = sim.judge
        start = setup.get("start", "play")
        if start == "play":
            referee.command("STARTROBOT")
        elif isinstance(start, dict):
            referee.command(
                start["command"], team=start.get("team", ""), spot=tuple(start["spot"]) if "spot" in start else None
            )
        elif start != "match":
            raise ValueError(f"{self.path}: setup.start must be 'play', 'match' or a table, not {start!r}")
        t0 = sim.time
        n_before = len(sim.events)
        script = sorted(d.get("script", []), key=lambda s: s["at"])
        k = 0
        steps = round(float(d.get("duration", 5.0)) / sim.dt)
        for _ in range(steps):
            while k < len(script) and sim.time - t0 >= script[k]["at"] - 1e-9:
                self._do(sim, script[k])
                k += 1
            sim.step()
            if sim.done:
                break
        events = []
        for ev in sim.events[n_before:]:
            ev = dict(ev)
            ev["t"] = round(ev["t"] - t0, 6)
            events.append(ev)
        for h in heard.values():
            h[:] = [(t - t0, c) for t, c in h]
        positions = {name: (st.x, st.y) for name, st in sim.model_states().items()}
        return Outcome(events, heard, sim.game, sim.judge.result(), t0, positions, sim if keep else None)

    def _until_stage(self, sim, stage: str) -> None:
        """Run the match until ``stage`` begins (at most a simulated hour)."""
        for _ in range(round(3600.0 / sim.dt)):
            if sim.judge.game()["stage"] == stage:
                return
            sim.step()
        raise ValueError(f"{self.path}: the match never reached stage {stage!r}")

    def _do(self, sim, item: dict) -> None:
        if "robot" in item:
            name = item["robot"]
            if "vel" in item:
                sim.send_vel(name, *item["vel"])
            if any(k in item for k in ("dribble", "kick", "lob")):
                sim.send_action(
                    name, dribble=item.get("dribble", False), kick=item.get("kick", 0.0), lob=item.get("lob", False)
                )
            if "place" in item:
                x, y, yaw = item["place"]
                sim.set_model_state(name, x=x, y=y, yaw=yaw)
        if "ball" in item:
            sim.set_model_state("ball", **item["ball"])
        if "operator" in item:
            op = dict(item["operator"])
            what = op.pop("op")
            ref = sim.judge
            if what == "command":
                ref.command(op["command"], team=op.get("team", ""), spot=tuple(op["spot"]) if "spot" in op else None)
            elif what == "place_ball":
                ref.place_ball(op["x"], op["y"])
            elif what == "send_off":
                ref.send_off(op["robot"], op.get("seconds"))
            elif what == "return":
                ref.return_robot(op["robot"])
            elif what == "card":
                ref.card(op["robot"], op["card"])
            elif what == "auto":
                ref.set_auto(op["on"])
            elif what == "goal":
                ref.award_goal(op["team"])
            else:
                getattr(ref, what)()

    # --- checking ----------------------------------------------------------------------------------------
    def check(self, out: Outcome) -> list[str]:
        """Every way the outcome differs from what the scenario states (empty: as expected)."""
        d = self.data
        problems: list[str] = []
        for exp in d.get("expect", []):
            if "heard" in exp:
                want = MatchMode[exp["heard"]]
                got = [t for t, c in out.heard[exp["team"]] if c == want and _within(exp, t)]
                if not got:
                    problems.append(f"{exp['team']} never heard {want.name}" + _window(exp))
                continue
            if not [e for e in out.events if _matches(exp, e)]:
                problems.append(f"no event matching {exp}")
        absent = d.get("absent", {})
        for e in out.events:
            if e["type"] in absent.get("types", []):
                problems.append(f"unexpected {e['type']} event: {e}")
        if self.legal:
            allowed = set(absent.get("allow", []))
            for e in out.events:
                if e["type"] in FOUL_TYPES and e["type"] not in allowed:
                    problems.append(f"a legal situation was flagged: {e}")
        for e in out.events:
            if e["type"] in FOUL_TYPES and not (e.get("team") and e.get("robot")):
                problems.append(f"a foul without its team and robot: {e}")
        for where in d.get("at_end", []):
            x, y = out.positions[where["model"]]
            for key, value, ok in (
                ("x_min", x, lambda v, b: v >= b),
                ("x_max", x, lambda v, b: v <= b),
                ("y_min", y, lambda v, b: v >= b),
                ("y_max", y, lambda v, b: v <= b),
            ):
                if key in where and not ok(value, where[key]):
                    problems.append(f"{where['model']} ends at ({x:.2f}, {y:.2f}), not {key} {where[key]}")
        final = d.get("final", {})
        for key, want in final.items():
            got = out.game.get(key)
            if got != want:
                problems.append(f"final {key}: expected {want!r}, got {got!r}")
        return problems


def _within(exp: dict, t: float) -> bool:
    lo, hi = exp.get("within", [-1e9, 1e9])
    return lo - 1e-9 <= t <= hi + 1e-9


def _window(exp: dict) -> str:
    return f" within {exp['within']}" if "within" in exp else ""


def _matches(exp: dict, e: dict) -> bool:
    for key, want in exp.items():
        if key in ("within", "value_min", "value_max", "detail_has"):
            continue
        # events leave zero fields out: robot = 0 matches an event without a robot
        got = e.get(key, 0 if isinstance(want, (int, float)) and not isinstance(want, bool) else None)
        if got != want:
            return False
    if not _within(exp, e["t"]):
        return False
    if "value_min" in exp and not e.get("value", 0.0) >= exp["value_min"]:
        return False
    if "value_max" in exp and not e.get("value", 0.0) <= exp["value_max"]:
        return False
    if "detail_has" in exp and exp["detail_has"] not in e.get("detail", ""):
        return False
    return True


def all_scenarios() -> list[Scenario]:
    return [Scenario.load(p) for p in sorted(SCENARIOS.glob("*.toml"))]
