"""`LearningRun`: a scene's run driven one control period at a time by a learning environment.

It is the embedded run (`simatch.Simulation`) and nothing else: the same physics, perception, strategies,
referee or judge, in the same lockstep order. The robots the scene hands to learning play `Learner`
strategies; at every control tick the run is held just before the ROBOT phase (`Simulation.step` with
``hold_before``), where every robot's perception and game command of the tick are out and no robot has
decided yet. The environment reads the learners' observations there, sets their commands, and the run goes
on to the next tick: so a learner decides on the same perception, at the same instant, as any robot of the
scene would, and the scripted robots decide beside it in the same phase.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from .. import msgs
from ..bus import Phase, topics
from ..config.loader import LoadedScene, SceneError, resolve, scene_from_text
from ..robots import model_class
from ..simulation import Simulation
from ..strategy.learner import Learner
from . import action as actions
from .observation import Layout
from .rewards import Agent, Snapshot, Step, make_terms, reward


def hand_over(
    scene: str | LoadedScene, learners: Iterable[str] | None, overrides: Mapping[str, Any] | None = None
) -> LoadedScene:
    """The scene with ``learners`` (team names, or robots ``team/id``) handed to learning, on top of what the
    scene itself hands over. With ``learners`` None and a scene that hands nobody over, its first team learns."""
    if isinstance(scene, LoadedScene):
        text, source, base = scene.text, scene.source, {**scene.overrides, **(overrides or {})}
    else:
        source, text = resolve(scene)
        base = dict(overrides or {})
    loaded = scene_from_text(text, source, base)
    spec = loaded.spec
    if learners is None:
        if spec.learner_names():
            return loaded
        learners = [next(iter(spec.teams))]
    if isinstance(learners, str):
        learners = [learners]
    extra: dict[str, Any] = {}
    for who in learners:
        team, _, rid = str(who).partition("/")
        if team not in spec.teams:
            raise SceneError(f"learners: the scene has no team {team!r} (teams: {', '.join(spec.teams)})")
        if not rid:
            extra[f"teams.{team}.strategy"] = "learner"
        elif not rid.isdigit() or int(rid) not in spec.teams[team].robot_ids():
            raise SceneError(f"learners: {who!r} is not a robot of the scene ({', '.join(spec.robot_names())})")
        else:
            ids = extra.setdefault(f"teams.{team}.learners", list(spec.teams[team].learners))
            if int(rid) not in ids:
                ids.append(int(rid))
    if not extra:
        raise SceneError("learners: name at least one team or robot")
    return scene_from_text(text, source, {**base, **extra})


class LearningRun:
    """One scene as a learning environment: its agents, their spaces' layouts, and the run of an episode."""

    def __init__(
        self,
        scene: str | LoadedScene = "msl_5v5",
        learners: Iterable[str] | None = None,
        overrides: Mapping[str, Any] | None = None,
        action_type: str = "box",
        max_vel: float | None = None,
        max_w: float | None = None,
        strict_actions: bool = False,
        teammates: int | None = None,
        obstacles: int | None = None,
        structures: int | None = None,
        episode_time: float | None = None,
    ):
        if action_type not in ("box", "discrete"):
            raise ValueError(f"action_type must be 'box' or 'discrete', got {action_type!r}")
        self.scene = hand_over(scene, learners, overrides)
        spec = self.scene.spec
        self.agents: list[str] = spec.learner_names()
        if not self.agents:
            raise SceneError(f"{self.scene.source}: no robot is handed to learning")
        self.action_type = action_type
        self.strict_actions = strict_actions
        self.control_steps = round(spec.control.period / spec.physics.timestep)
        self.period = spec.control.period
        self.terms = make_terms(spec.learning.rewards, self.scene.source)
        self.end_on = frozenset(spec.learning.end_on)
        self.episode_time = episode_time if episode_time is not None else spec.learning.episode_time
        geo = spec.world.geometry()
        n_robots = len(spec.robot_names())
        self.info: dict[str, Agent] = {}
        self.limits: dict[str, actions.Limits] = {}
        self.layouts: dict[str, Layout] = {}
        self.teammate_ids: dict[str, list[int]] = {}
        self.team_of_robot = {name: name.partition("/")[0] for name in spec.robot_names()}
        # in a scene with aerial robots every observation has their heights (docs/aerial.md)
        self.airborne = airborne = any(
            model_class(m.model).locomotion == "aerial" for t in spec.teams.values() for m in t.members()
        )
        for name in self.agents:
            team, _, rid = name.partition("/")
            tspec = spec.teams[team]
            self.info[name] = Agent(name, team, geo.half_length)
            member = next(m for m in tspec.members() if m.id == int(rid))  # (a squad may hold other models)
            model = model_class(member.model)(member.model_params)
            self.limits[name] = actions.Limits.of(model, spec.kicker, max_vel, max_w)
            self.teammate_ids[name] = [r for r in tspec.robot_ids() if r != int(rid)]
            t = len(tspec.robot_ids()) - 1 if teammates is None else teammates
            k = n_robots - 1 if obstacles is None else obstacles
            m = len(geo.obstacles) if structures is None else structures
            self.layouts[name] = Layout(t, k, geo.half_length, heights=airborne, structures=m)
        self.sim: Simulation | None = None
        self.closed = False
        self.over = True  # no episode in progress
        self._events: list = []
        self._learners: dict[str, Learner] = {}
        self._snapshot: Snapshot | None = None
        self.end_reason: str | None = None

    # --- the episode -------------------------------------------------------------------------------------------
    def check_open(self) -> None:
        if self.closed:
            raise RuntimeError("this simatch environment is closed: make a new one")

    def reset(self, seed: int) -> dict[str, np.ndarray]:
        """A new episode: the scene's run with ``seed``, held at its first control tick. Observations."""
        self.check_open()
        if self.sim is not None:
            self.sim.close()
        self.sim = sim = Simulation(self.scene, seed=int(seed))
        self._events = []
        sim.bus.subscribe(topics.EVENTS, msgs.GameEvent, self._events.append)
        self._learners = {}
        # a robot of each team, whose frame tells the side the team attacks now (it turns when ends change)
        self._team_rows = {team: sim.simulator.team_of.index(team) for team in self.scene.spec.teams}
        for name in self.agents:
            node = sim.robot_nodes.get(name)
            if node is None or not isinstance(node.strategy, Learner):
                raise SceneError(f"{self.scene.source}: {name} plays no Learner strategy")
            self._learners[name] = node.strategy
        sim.step(0, hold_before=Phase.ROBOT)
        self._snapshot = self.snapshot()
        self.over = False
        self.end_reason = None
        return self.observations()

    def decode(self, actions_by_agent: Mapping[str, Any]) -> dict:
        """Every agent's Command, checked as a whole before anything is applied (ValueError otherwise)."""
        if not isinstance(actions_by_agent, Mapping):
            raise ValueError(f"actions must be a dict agent -> action, got {type(actions_by_agent).__name__}")
        unknown = sorted(set(actions_by_agent) - set(self.agents))
        if unknown:
            raise ValueError(f"actions for unknown agent(s) {', '.join(map(str, unknown))}; agents: {self.agents}")
        missing = [a for a in self.agents if a not in actions_by_agent]
        if missing:
            raise ValueError(f"no action for agent(s) {', '.join(missing)}")
        out = {}
        for name in self.agents:
            a = actions_by_agent[name]
            lim = self.limits[name]
            if self.action_type == "box":
                out[name] = lim.command(actions.check_box(name, a, self.strict_actions, lim.size))
            else:
                out[name] = lim.discrete(actions.check_discrete(name, a, lim.moves))
        return out

    def step(self, actions_by_agent: Mapping[str, Any]):
        """One control period: (observations, rewards, terminated, truncated, infos) of every agent."""
        self.check_open()
        if self.over or self.sim is None:
            raise RuntimeError("the episode is over: call reset() first")
        commands = self.decode(actions_by_agent)
        for name, cmd in commands.items():
            self._learners[name].act(cmd)
        sim = self.sim
        first = len(self._events)
        sim.step(self.control_steps, hold_before=Phase.ROBOT)
        events = self._events[first:]
        after = self.snapshot()
        step = Step(self._snapshot, after, events, self.period)
        self._snapshot = after
        terminated = truncated = False
        # a decision the scene ends episodes on; else the time is up (a cut: truncation); else the judge ended
        # the run on its own (end of the match, every target captured)
        ended = [ev.type for ev in events if ev.type in self.end_on]
        if ended:
            terminated, self.end_reason = True, ended[0]
        elif self.episode_time is not None and sim.time >= self.episode_time - 1e-9:
            truncated, self.end_reason = True, "episode_time"
        elif sim.duration is not None and sim.time >= sim.duration - 1e-9:
            truncated, self.end_reason = True, "time_limit"
        elif sim.done:
            terminated, self.end_reason = True, "judge"
        self.over = terminated or truncated
        rewards, infos = {}, {}
        for name in self.agents:
            r, parts = reward(self.terms, step, self.info[name])
            rewards[name] = r
            infos[name] = {"rewards": parts, "time": sim.time}
            if self.over:
                infos[name]["end"] = self.end_reason
        obs = self.observations()
        return obs, rewards, dict.fromkeys(self.agents, terminated), dict.fromkeys(self.agents, truncated), infos

    def observations(self) -> dict[str, np.ndarray]:
        out = {}
        nodes = self.sim.robot_nodes
        for name in self.agents:
            world = nodes[name].world
            out[name] = self.layouts[name].encode(
                world.vision, world.coach, self.teammate_ids[name], world.field.obstacles
            )
        return out

    def snapshot(self) -> Snapshot:
        sim = self.sim.simulator
        names, pose, _ = sim.model_state_arrays()
        robots = {name: (float(pose[k, 0]), float(pose[k, 1])) for k, name in enumerate(names[:-1])}
        b = pose[-1]
        holder = sim.ball.holder
        team = self.team_of_robot[sim.robot_names[holder]] if holder >= 0 else ""
        attacks = {t: int(sim.signs[i]) for t, i in self._team_rows.items()}
        return Snapshot((float(b[0]), float(b[1]), float(b[2])), robots, team, attacks)

    def close(self) -> None:
        if self.sim is not None:
            self.sim.close()
            self.sim = None
        self.closed = True
        self.over = True
