"""What happened in a match, in numbers: the analysis behind a match report and a tournament's table.

`MatchAnalysis` is fed the run's messages as they come, live from the bus (`simatch.report.live`) or read
back from a recording (`simatch.report.recorded`), and gives the same numbers either way: it keeps what it
is fed in compact logs (positions at every control tick, changes of who touches the ball, kicks, events,
game states, roles) and computes everything in `finish`, so the order in which messages of one physics step
arrive does not matter.

What it computes (`finish` returns a plain, JSON-able dict; the keys are documented in docs/report.md):

* **possession**: the team that last touched the ball alone has it (a duel keeps it with the team that had
  it), counted while the ball is in play (phase ``play`` of the referee; the whole run without a referee),
  in total and per time bin;
* **shots**: a kick (the kicker fired, from ``ball_contacts``) whose ball, just after the kick, heads for the
  goal the kicker's team attacks (its path crosses that goal line within `SHOT_WIDE` of a post) from within
  `SHOT_RANGE` of that goal line, fast enough to roll that far (or lobbed); its outcome is what came first:
  goal, disallowed, saved (the defending goalkeeper touched it), blocked (another opponent), team-mate, off
  target (ball out), stopped (a stoppage or nothing within `SHOT_FOLLOW` seconds);
* **heat maps** (seconds spent per 0.5 m cell) of the ball and of each team's robots, during play;
* per robot **distance** run and **top speed**; **role time** from StrategyInfo; the **stages** and phases
  of play; the score over time and every event (goals, fouls, cards, restarts with their reasons).

Every position is given in one *view frame* for the whole match: the first team (``teams[0]``, cyan in
``msl_5v5``) attacks +x. After a change of ends a sample is turned by pi, so a team's play stays on the end
it attacks in the report.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..field import FieldGeometry
from ..scene.referee.log import FOUL_TYPES
from ..simulation import event_dict
from ..strategy.roles import role_name

HEAT_CELL = 0.5  # [m] side of a heat-map cell
SHOT_RANGE = 11.0  # [m] a kick farther than this from the attacked goal line is no shot
SHOT_WIDE = 1.0  # [m] a path crossing the goal line this far outside a post still counts as a shot (off target)
SHOT_MIN_SPEED = 1.0  # [m/s] the ball must move towards the goal at least this fast just after the kick
SHOT_FOLLOW = 10.0  # [s] a shot with no outcome after this long is "stopped"
SHOT_OWN_TOUCH = 0.3  # [s] the kicker's own contacts with the ball this soon after its kick are the kick itself
TELEPORT = 0.5  # [m] a robot moving farther than this in one control period was placed, not driven
ROLE_GAP = 0.5  # [s] a robot silent for longer than this is counted in no role meanwhile

CARD_TYPES = frozenset({"yellow_card", "red_card", "send_off", "robot_returned"})
RESTART_TYPES = frozenset({"ball_out", "restart_timeout", "no_progress", "ball_placed", "ball_in_play"})
ON_TARGET = frozenset({"goal", "disallowed", "saved"})
OUTCOMES = ("goal", "disallowed", "saved", "blocked", "team-mate", "off target", "stopped")


def event_category(ev: dict) -> str:
    """Where an event goes on the report's timeline."""
    kind = ev["type"]
    if kind in ("goal", "goal_disallowed", "shootout_kick"):
        return "goals"
    if kind in FOUL_TYPES:
        return "fouls"
    if kind in CARD_TYPES:
        return "cards"
    if kind in RESTART_TYPES or (kind == "command" and ev.get("team")):
        return "restarts"
    if kind in ("stage", "match_end"):
        return "stages"
    return "other"


@dataclass
class TeamInfo:
    name: str
    colour: str
    strategy: str
    goalkeeper: int | None
    sign: int  # +1: attacks +x at the start of the match


@dataclass
class MatchMeta:
    """What the analysis needs to know of the run before it starts."""

    scene: str
    seed: int
    teams: list[TeamInfo]
    field: FieldGeometry
    dt: float
    control_period: float
    refereed: bool
    ball_deceleration: float = 0.5  # [m/s^2] of a freely rolling ball
    labels: dict[str, str] = field(default_factory=dict)  # team -> a name to show (a tournament's entry)

    @classmethod
    def of_scene(cls, loaded, seed: int, labels: dict[str, str] | None = None) -> MatchMeta:
        spec = loaded.spec
        teams = [
            TeamInfo(
                name=name,
                colour=t.color or name,
                strategy=t.strategy,
                goalkeeper=t.goalkeeper,
                sign=spec.team_sign(name),
            )
            for name, t in spec.teams.items()
        ]
        return cls(
            scene=loaded.name,
            seed=int(seed),
            teams=teams,
            field=spec.world.geometry(),
            dt=spec.physics.timestep,
            control_period=spec.control.period,
            refereed=spec.judge.kind == "msl_referee",
            ball_deceleration=spec.ball.rolling_deceleration,
            labels=dict(labels or {}),
        )

    def describe(self) -> dict:
        return {
            "scene": self.scene,
            "seed": self.seed,
            "teams": [
                {
                    "name": t.name,
                    "colour": t.colour,
                    "strategy": t.strategy,
                    "label": self.labels.get(t.name, t.strategy),
                    "goalkeeper": t.goalkeeper,
                }
                for t in self.teams
            ],
            "field": self.field.describe(),
            "dt": self.dt,
            "control_period": self.control_period,
            "refereed": self.refereed,
        }


def _team_of(robot: str) -> str:
    return robot.split("/", 1)[0]


def _rid_of(robot: str) -> int:
    try:
        return int(robot.rsplit("/", 1)[1])
    except (IndexError, ValueError):
        return 0


class MatchAnalysis:
    """Fed a run's messages (any order within a physics step), gives the match in numbers (`finish`)."""

    def __init__(self, meta: MatchMeta):
        self.meta = meta
        self.control_steps = max(1, round(meta.control_period / meta.dt))
        self.names: list[str] | None = None
        self._t: list[float] = []
        self._steps: list[int] = []
        self._pos: list[np.ndarray] = []  # (M, 2) float32 per sample, world frame
        self._vel: list[np.ndarray] = []
        self._contacts: list[tuple[int, float, frozenset]] = []  # (step, t, robots touching or holding)
        self._last_contact_step = -2
        self._last_set: frozenset = frozenset()
        self._kicks: list[tuple[int, float, str, float, bool]] = []  # (step, t, robot, speed, lob)
        self._events: list[tuple[float, int, dict]] = []
        self._states: list[tuple[float, str, str, tuple]] = []  # (t, stage, phase, score) on change
        self._sides: list[tuple[float, dict[str, int]]] = [(0.0, {t.name: t.sign for t in meta.teams})]
        self._roles: dict[str, dict[str, float]] = {}
        self._role_last: dict[str, tuple[float, str]] = {}
        self._end = 0.0

    # --- feeding ---------------------------------------------------------------------------------------------
    def states(self, step: int, names: list[str], pose: np.ndarray, twist: np.ndarray) -> None:
        """Model states of physics step ``step`` (world frame, float32 as published): kept at control ticks
        only. Their time is the step's, as the run's nodes compute it (``step * dt``), live or read back."""
        if step % self.control_steps:
            return
        t = step * self.meta.dt
        if self.names is None:
            self.names = list(names)
        elif list(names) != self.names:
            return  # a world that changed its models mid-run: keep to the first set
        pose = np.asarray(pose, dtype=np.float32).reshape(len(names), -1)
        twist = np.asarray(twist, dtype=np.float32).reshape(len(names), -1)
        self._t.append(float(t))
        self._steps.append(int(step))
        self._pos.append(pose[:, :2].copy())
        self._vel.append(twist[:, :2].copy())
        self._end = max(self._end, float(t))

    def contacts(self, t: float, step: int, touching: Iterable[str], holder: str, kicker: str, speed: float, lob: bool):
        """A BallContacts message (published only on steps where something touches, holds or kicks the ball)."""
        now = frozenset([*touching, holder] if holder else touching)
        if step != self._last_contact_step + 1 and self._last_set:
            # no message in between: nobody touched the ball from the step after the last message on
            gap = self._last_contact_step + 1
            self._contacts.append((gap, gap * self.meta.dt, frozenset()))
            self._last_set = frozenset()
        if now != self._last_set:
            self._contacts.append((int(step), int(step) * self.meta.dt, now))
            self._last_set = now
        self._last_contact_step = int(step)
        if kicker:
            self._kicks.append((int(step), int(step) * self.meta.dt, kicker, float(speed), bool(lob)))
        self._end = max(self._end, float(t))

    def event(self, ev) -> None:
        """A GameEvent (message) or an event as ``sim.events`` gives it."""
        d = ev if isinstance(ev, dict) else event_dict(ev)
        self._events.append((d["t"], len(self._events), d))
        self._end = max(self._end, d["t"])

    def game_state(self, t: float, stage: str, phase: str, score: Iterable[int]) -> None:
        """The referee's GameState: stage, phase of play and score (in the order of the scene's teams)."""
        key = (stage, phase, tuple(int(s) for s in score))
        if not self._states or self._states[-1][1:] != (stage, phase, key[2]):
            self._states.append((float(t), stage, phase, key[2]))
        self._end = max(self._end, float(t))

    def sides(self, t: float, signs: dict[str, int]) -> None:
        """Each team's attacking direction from ``t`` on (+1: towards +x), after a change of ends."""
        if signs != self._sides[-1][1]:
            self._sides.append((float(t), dict(signs)))

    def game_state_message(self, m) -> None:
        """A GameState message: stage, phase and score, and each team's side where the referee says it
        (``attacks``: "+x"/"-x" per team; a producer that predates the field leaves it empty)."""
        self.game_state(m.stamp, m.stage, m.phase, m.score)
        attacks = list(getattr(m, "attacks", None) or ())
        if attacks and len(attacks) == len(m.teams):
            self.sides(m.stamp, {team: (1 if side == "+x" else -1) for team, side in zip(m.teams, attacks)})

    def strategy(self, t: float, robot: str, role: int) -> None:
        """A robot's StrategyInfo: its role from ``t`` on."""
        name = role_name(int(role))
        last = self._role_last.get(robot)
        if last is not None:
            gap = t - last[0]
            if 0 < gap <= ROLE_GAP:
                roles = self._roles.setdefault(robot, {})
                roles[last[1]] = roles.get(last[1], 0.0) + gap
        self._role_last[robot] = (float(t), name)

    # --- the numbers -------------------------------------------------------------------------------------------
    def finish(self, extra: dict[str, Any] | None = None) -> dict:
        """Everything the report shows, as plain data. ``extra``: the run's own result, digest and so on."""
        meta = self.meta
        teams = [t.name for t in meta.teams]
        end = self._end
        times = np.asarray(self._t, dtype=float)
        names = self.names or []
        pos = np.stack(self._pos) if self._pos else np.zeros((0, len(names), 2), np.float32)
        vel = np.stack(self._vel) if self._vel else np.zeros((0, len(names), 2), np.float32)
        events = [d for _, _, d in sorted(self._events, key=lambda e: (e[0], e[1]))]
        play = self._play_intervals(end)
        view = self._view_signs(times)  # +1/-1 per sample: world -> view frame
        in_play = _inside(times, play)
        out: dict[str, Any] = {
            "meta": meta.describe(),
            "duration": round(end, 6),
            "play_seconds": round(sum(b - a for a, b in play), 3),
            "sides": [{"t": t, "signs": s} for t, s in self._sides],
        }
        out["possession"] = self._possession(play, end)
        out["shots"] = self._shots(times, pos, vel, view, events)
        out["heat"] = self._heat(names, pos, view, in_play)
        out["robots"] = self._robots(names, pos, vel)
        out["roles"] = self._role_time()
        out["stages"], out["phases"] = self._stages(end)
        out["score_timeline"] = self._score_timeline(events, teams)
        for ev in events:
            ev["category"] = event_category(ev)
        out["events"] = events
        out["summary"] = self._summary(out, teams)
        if extra:
            out.update(extra)
        return out

    # ---- the parts
    def _play_intervals(self, end: float) -> list[tuple[float, float]]:
        """When the ball was in play: the referee's phase ``play``; the whole run where nobody referees."""
        if not self.meta.refereed or not self._states:
            return [(0.0, end)] if end > 0 else []
        out = []
        start = None
        for t, _, phase, _ in self._states:
            if phase == "play" and start is None:
                start = t
            elif phase != "play" and start is not None:
                out.append((start, t))
                start = None
        if start is not None and end > start:
            out.append((start, end))
        return out

    def _sign_at(self, team: str, t: float) -> int:
        sign = self._sides[0][1].get(team, 1)
        for since, signs in self._sides:
            if since <= t:
                sign = signs.get(team, sign)
            else:
                break
        return sign

    def _view_signs(self, times: np.ndarray) -> np.ndarray:
        first = self.meta.teams[0].name
        out = np.full(len(times), self._sides[0][1].get(first, 1), dtype=np.float32)
        for since, signs in self._sides[1:]:
            out[times >= since] = signs.get(first, 1)
        return out

    def _possession(self, play: list[tuple[float, float]], end: float) -> dict:
        teams = [t.name for t in self.meta.teams]
        # who has the ball from each change on: the team of the robots touching it alone
        owner_changes: list[tuple[float, str]] = []
        owner = ""
        for _, t, robots in self._contacts:
            touching = {_team_of(r) for r in robots}
            if len(touching) == 1:
                team = next(iter(touching))
                if team != owner:
                    owner = team
                    owner_changes.append((t, team))
        width = _bin_width(end)
        nbins = max(1, math.ceil(end / width)) if end > 0 else 0
        per_bin = {team: [0.0] * nbins for team in teams}
        total = dict.fromkeys(teams, 0.0)
        # walk the play intervals against the owner changes
        bounds = owner_changes + [(math.inf, "")]
        for a, b in play:
            owner = ""
            k = 0
            while k < len(bounds) - 1 and bounds[k][0] <= a:
                owner = bounds[k][1]
                k += 1
            cursor = a
            while cursor < b:
                nxt = min(b, bounds[k][0])
                if owner in total:
                    total[owner] += nxt - cursor
                    _spread(per_bin[owner], cursor, nxt, width)
                if nxt >= b:
                    break
                cursor = nxt
                owner = bounds[k][1]
                k += 1
        held = sum(total.values())
        share = {team: (round(total[team] / held, 4) if held > 0 else None) for team in teams}
        bins = []
        for i in range(nbins):
            s = sum(per_bin[team][i] for team in teams)
            bins.append(
                {
                    "t0": i * width,
                    "t1": min(end, (i + 1) * width),
                    "seconds": {team: round(per_bin[team][i], 3) for team in teams},
                    "share": {team: (round(per_bin[team][i] / s, 4) if s > 0 else None) for team in teams},
                }
            )
        return {
            "seconds": {team: round(total[team], 3) for team in teams},
            "share": share,
            "bin_seconds": width,
            "bins": bins,
        }

    def _touch_after(self, step: int, kicker: str, t_kick: float) -> tuple[float, str] | None:
        """The first robot (other than the kicker right after its own kick) to touch the ball after ``step``."""
        for s, t, robots in self._contacts:
            if s <= step:
                continue
            for robot in sorted(robots):
                if robot == kicker and t - t_kick < SHOT_OWN_TOUCH:
                    continue
                return t, robot
        return None

    def _shots(self, times, pos, vel, view, events: list[dict]) -> list[dict]:
        if not len(times) or self.names is None or "ball" not in self.names:
            return []
        meta = self.meta
        f = meta.field
        b = self.names.index("ball")
        goalkeepers = {t.name: t.goalkeeper for t in meta.teams}
        out = []
        kicks = sorted(self._kicks)
        for step, t, robot, speed, lob in kicks:
            i = int(np.searchsorted(times, t - 1e-9))  # the first sample at or after the kick
            if i >= len(times) or times[i] - t > 2 * meta.control_period:
                continue
            team = _team_of(robot)
            sign = self._sign_at(team, t)
            x, y = float(pos[i, b, 0]), float(pos[i, b, 1])
            vx, vy = float(vel[i, b, 0]), float(vel[i, b, 1])
            toward = sign * vx
            if toward < SHOT_MIN_SPEED:
                continue
            goal_x = sign * f.half_length
            if abs(goal_x - x) > SHOT_RANGE:
                continue
            y_at = y + vy * (goal_x - x) / vx
            if abs(y_at) > 0.5 * f.goal_width + SHOT_WIDE:
                continue
            if not lob and not self._reaches(math.hypot(vx, vy), math.hypot(goal_x - x, y_at - y)):
                continue  # a ball rolling out before the goal line: a pass, not a shot
            outcome, t_out, detail = self._outcome(step, t, robot, team, events, goalkeepers)
            v = float(view[i])
            out.append(
                {
                    "t": round(t, 3),
                    "team": team,
                    "robot": robot,
                    "x": round(v * x, 3),
                    "y": round(v * y, 3),
                    "goal_y": round(v * y_at, 3),
                    "goal_x": round(v * goal_x, 3),
                    "speed": round(speed, 2),
                    "lob": lob,
                    "distance": round(math.hypot(goal_x - x, y), 2),
                    "outcome": outcome,
                    "on_target": outcome in ON_TARGET,
                    "outcome_t": round(t_out, 3) if t_out is not None else None,
                    "detail": detail,
                }
            )
        return out

    def _reaches(self, speed: float, distance: float) -> bool:
        """A ground ball at ``speed`` rolls at least ``distance`` before it stops."""
        decel = self.meta.ball_deceleration
        return decel <= 0 or speed * speed / (2.0 * decel) >= distance

    def _outcome(self, step, t, robot, team, events, goalkeepers) -> tuple[str, float | None, str]:
        touch = self._touch_after(step, robot, t)
        t_touch = touch[0] if touch else math.inf
        for ev in events:
            if ev["t"] < t:
                continue
            if ev["t"] > min(t_touch, t + SHOT_FOLLOW):
                break
            kind = ev["type"]
            if kind == "goal":
                return ("goal" if ev.get("team") == team else "stopped"), ev["t"], ev.get("detail", "")
            if kind == "goal_disallowed":
                return "disallowed", ev["t"], ev.get("detail", "")
            if kind == "ball_out":
                return "off target", ev["t"], ev.get("detail", "")
            if kind == "command" or kind in FOUL_TYPES or kind == "stage":
                if ev["t"] < t_touch and ev["t"] > t:
                    return "stopped", ev["t"], ev.get("detail", "")
        if touch is not None and t_touch <= t + SHOT_FOLLOW:
            other = touch[1]
            other_team = _team_of(other)
            if other_team == team:
                return "team-mate", t_touch, f"touched next by {other}"
            if goalkeepers.get(other_team) == _rid_of(other):
                return "saved", t_touch, f"saved by {other} (goalkeeper)"
            return "blocked", t_touch, f"blocked by {other}"
        return "stopped", None, "no touch, goal or stoppage within 10 s"

    def _heat(self, names, pos, view, in_play) -> dict:
        f = self.meta.field
        hx = f.half_length + f.margin
        hy = f.half_width + f.margin
        nx = max(1, round(2 * hx / HEAT_CELL))
        ny = max(1, round(2 * hy / HEAT_CELL))
        xe = np.linspace(-hx, hx, nx + 1)
        ye = np.linspace(-hy, hy, ny + 1)
        period = self.meta.control_period
        out: dict[str, Any] = {
            "x_edges": [round(float(v), 4) for v in xe],
            "y_edges": [round(float(v), 4) for v in ye],
            "maps": {},
        }
        if not len(pos):
            return out
        sel = in_play
        groups: dict[str, list[int]] = {"ball": [names.index("ball")] if "ball" in names else []}
        for team in self.meta.teams:
            groups[team.name] = [k for k, n in enumerate(names) if _team_of(n) == team.name and n != "ball"]
        for key, cols in groups.items():
            if not cols:
                continue
            p = pos[sel][:, cols, :].astype(float) * view[sel][:, None, None]
            h, _, _ = np.histogram2d(p[..., 0].ravel(), p[..., 1].ravel(), bins=[xe, ye])
            # rows = y, columns = x (as a heat map is drawn); seconds per cell
            out["maps"][key] = np.round(h.T * period, 4).tolist()
        return out

    def _robots(self, names, pos, vel) -> list[dict]:
        out = []
        if not len(pos):
            return out
        step = np.linalg.norm(np.diff(pos.astype(float), axis=0), axis=2)  # (S-1, M)
        moved = np.where(step <= TELEPORT, step, 0.0).sum(axis=0)
        speed = np.linalg.norm(vel.astype(float), axis=2).max(axis=0)
        for k, name in enumerate(names):
            out.append(
                {
                    "name": name,
                    "team": _team_of(name) if name != "ball" else "",
                    "distance": round(float(moved[k]), 2),
                    "top_speed": round(float(speed[k]), 3),
                }
            )
        return out

    def _role_time(self) -> dict:
        out = {}
        for robot in sorted(self._roles, key=lambda r: (_team_of(r), _rid_of(r))):
            out[robot] = {role: round(sec, 3) for role, sec in sorted(self._roles[robot].items())}
        return out

    def _stages(self, end: float) -> tuple[list[dict], list[dict]]:
        stages: list[dict] = []
        phases: list[dict] = []
        for t, stage, phase, _ in self._states:
            if not stages or stages[-1]["stage"] != stage:
                if stages:
                    stages[-1]["t1"] = t
                stages.append({"stage": stage, "t0": t, "t1": end})
            if not phases or phases[-1]["phase"] != phase:
                if phases:
                    phases[-1]["t1"] = t
                phases.append({"phase": phase, "t0": t, "t1": end})
        return stages, phases

    def _score_timeline(self, events: list[dict], teams: list[str]) -> list[dict]:
        score = dict.fromkeys(teams, 0)
        out = [{"t": 0.0, "score": dict(score)}]
        for ev in events:
            if ev["type"] == "goal" and ev.get("team") in score:
                score[ev["team"]] += 1
                out.append({"t": ev["t"], "score": dict(score), "team": ev["team"], "detail": ev.get("detail", "")})
        return out

    def _summary(self, out: dict, teams: list[str]) -> dict:
        """Per team: the few numbers a table of many matches keeps."""
        shots = out["shots"]
        fouls = {t: 0 for t in teams}
        cards = {t: {"yellow": 0, "red": 0} for t in teams}
        errors: dict[str, dict[str, float]] = {t: {} for t in teams}
        for ev in out["events"]:
            team = ev.get("team")
            if team not in fouls:
                continue
            if ev["type"] in FOUL_TYPES:
                fouls[team] += 1
            elif ev["type"] == "yellow_card":
                cards[team]["yellow"] += 1
            elif ev["type"] == "red_card":
                cards[team]["red"] += 1
            elif ev["type"] == "strategy_error":  # logged at the 1st error of a robot and every 100th
                robot = str(ev.get("robot", ""))
                errors[team][robot] = max(errors[team].get(robot, 0.0), float(ev.get("value", 1.0)))
        goals = out["score_timeline"][-1]["score"]
        return {
            team: {
                "goals": goals.get(team, 0),
                "shots": sum(1 for s in shots if s["team"] == team),
                "on_target": sum(1 for s in shots if s["team"] == team and s["on_target"]),
                "possession": out["possession"]["share"].get(team),
                "fouls": fouls[team],
                "yellow_cards": cards[team]["yellow"],
                "red_cards": cards[team]["red"],
                "strategy_errors": int(sum(errors[team].values())),
                "distance": round(sum(r["distance"] for r in out["robots"] if r["team"] == team), 1),
            }
            for team in teams
        }


def _bin_width(duration: float) -> float:
    """A round bin width giving about 24 bins over the match."""
    for width in (5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0):
        if duration / width <= 30:
            return width
    return 1800.0


def _spread(bins: list[float], a: float, b: float, width: float) -> None:
    """Add the seconds from ``a`` to ``b`` to the bins they fall in."""
    while a < b:
        i = int(a // width)
        edge = (i + 1) * width
        part = min(b, edge) - a
        if i < len(bins):
            bins[i] += part
        a = min(b, edge)


def _inside(times: np.ndarray, intervals: list[tuple[float, float]]) -> np.ndarray:
    mask = np.zeros(len(times), dtype=bool)
    for a, b in intervals:
        mask |= (times >= a) & (times < b)
    return mask
