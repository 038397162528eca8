"""Who serves which robot: the processes registered with a server, and their state.

A process (``simatch team`` or ``simatch robot``) joins for some robots of one team. It is *active* while it
answers every tick; one that misses a tick's deadline becomes *late* (the server stops waiting for it, its
robots stop by the watchdog) and active again with its next answer; one that says goodbye or whose liveliness
token vanishes (it died) is *gone*, and its robots are free for a restarted process to take over.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from ..config.schema import Scene


class ProcState(enum.Enum):
    ACTIVE = "active"
    LATE = "late"
    GONE = "gone"


@dataclass
class Proc:
    id: str
    team: str
    robots: list[int]
    kind: str  # "team" or "robot"
    strategy_pub: bool  # runs its team's StrategyPub itself
    joined_step: int
    state: ProcState = ProcState.ACTIVE
    missed: int = 0  # ticks it did not answer in time
    streak: int = 0  # ... in a row
    answered: int = 0
    host: str = ""
    phase: int = 0  # the physics step of the control period its ticks open at (protocol.phase_of)

    @property
    def label(self) -> str:
        names = ",".join(str(r) for r in self.robots)
        return f"{self.kind} process {self.id} ({self.team}/{names})"


class JoinError(ValueError):
    """A join the server refuses; the message says why (sent back to the process)."""


@dataclass
class Registry:
    scene: Scene
    procs: dict[str, Proc] = field(default_factory=dict)
    owner: dict[str, str] = field(default_factory=dict)  # robot name -> proc id

    def expected_robots(self) -> dict[str, list[int]]:
        """The robots a server waits for: every robot of every team that has a strategy (not 'none')."""
        return {team: spec.robot_ids() for team, spec in self.scene.teams.items() if spec.strategy != "none"}

    def join(self, proc: Proc) -> list[Proc]:
        """Register ``proc`` (JoinError if it may not serve its robots); returns the hung processes it replaces."""
        teams = self.scene.teams
        if proc.team not in teams:
            raise JoinError(f"this scene has no team {proc.team!r} (teams: {', '.join(teams)})")
        ids = teams[proc.team].robot_ids()
        unknown = [r for r in proc.robots if r not in ids]
        if unknown or not proc.robots:
            raise JoinError(f"team {proc.team} has no robot(s) {unknown or '(none given)'}; its robots are {ids}")
        if proc.id in self.procs and self.procs[proc.id].state is not ProcState.GONE:
            raise JoinError(f"process {proc.id} has already joined")
        for rid in proc.robots:
            holder = self.procs.get(self.owner.get(f"{proc.team}/{rid}", ""))
            if holder is not None and holder.state is ProcState.ACTIVE:
                raise JoinError(f"{proc.team}/{rid} is already served by {holder.label}")
        replaced = []
        for rid in proc.robots:
            old = self.procs.get(self.owner.get(f"{proc.team}/{rid}", ""))
            if old is not None and old.state is ProcState.LATE:  # a hung process is replaced
                replaced.append(self.leave(old.id))
            self.owner[f"{proc.team}/{rid}"] = proc.id
        self.procs[proc.id] = proc
        return [p for p in replaced if p is not None]

    def leave(self, proc_id: str) -> Proc | None:
        proc = self.procs.get(proc_id)
        if proc is None or proc.state is ProcState.GONE:
            return None
        proc.state = ProcState.GONE
        for rid in proc.robots:
            name = f"{proc.team}/{rid}"
            if self.owner.get(name) == proc_id:
                del self.owner[name]
        return proc

    def active(self) -> list[Proc]:
        return [p for p in self.procs.values() if p.state is ProcState.ACTIVE]

    def served(self, team: str) -> list[int]:
        return sorted(
            int(name.split("/")[1])
            for name, pid in self.owner.items()
            if name.startswith(team + "/") and self.procs[pid].state is not ProcState.GONE
        )

    def missing(self) -> dict[str, list[int]]:
        """Expected robots nobody serves, per team (teams with none missing left out)."""
        out = {}
        for team, ids in self.expected_robots().items():
            served = set(self.served(team))
            lacking = [r for r in ids if r not in served]
            if lacking:
                out[team] = lacking
        return out

    def team_has_strategy_pub(self, team: str) -> bool:
        return any(p.strategy_pub and p.team == team and p.state is not ProcState.GONE for p in self.procs.values())
