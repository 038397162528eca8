"""Scenario helpers for strategy tests: a msl_5v5 run with chosen strategies, robots placed by hand, the
others benched off the field, and watchers of what happened to the ball."""

from __future__ import annotations

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import mirror

BENCH_Y = 8.2  # beyond the 1 m margin: a benched robot is not "valid" (not on the field)


def scenario(cyan: str = "nubot", magenta: str = "none", seed: int = 0, **overrides) -> simatch.Simulation:
    """msl_5v5 with these strategies and no referee: the test gives the game commands (coaches)."""
    ov = {"teams.cyan.strategy": cyan, "teams.magenta.strategy": magenta, "judge.kind": "none"}
    ov.update(overrides)
    return simatch.Simulation("msl_5v5", seed=seed, overrides=ov)


def bench_all_but(sim, keep: list[str]) -> None:
    """Every robot not in ``keep`` leaves the field (beside it, beyond the margin) and stands still there."""
    x = -10.0
    for name in sim.simulator.robot_names:
        if name in keep:
            continue
        sim.set_model_state(name, x=x, y=-BENCH_Y, yaw=0.0, vx=0.0, vy=0.0, wz=0.0)
        sim.take_control(name)
        x += 0.8


def command(sim, team: str, cmd: int, **fields) -> None:
    """A game command for ``team`` (the other team hears it mirrored), as a referee would give it."""
    for t, coach in sim.coaches.items():
        coach.send(cmd if t == team else mirror(cmd), **fields)


def start(sim) -> None:
    for coach in sim.coaches.values():
        coach.start_play()


class BallWatch:
    """Who holds and kicks the ball, step by step (the simulator's ball_contacts), and goals."""

    def __init__(self, sim):
        self.sim = sim
        self.holders: list[tuple[float, str]] = []
        self.kicks: list[tuple[float, str, float]] = []
        self.touches: list[tuple[float, str]] = []
        sim.bus.subscribe(topics.BALL_CONTACTS, msgs.BallContacts, self._on)

    def _on(self, m) -> None:
        if m.holder and (not self.holders or self.holders[-1][1] != m.holder):
            self.holders.append((m.stamp, m.holder))
        if m.kicker:
            self.kicks.append((m.stamp, m.kicker, m.kick_speed))
        for name in list(m.touching) + [n for n in (m.holder, m.kicker) if n]:
            if not self.touches or self.touches[-1][1] != name:
                self.touches.append((m.stamp, name))

    def held_by(self, name: str) -> bool:
        return any(h == name for _, h in self.holders)


def goal_side(sim) -> int:
    """+1 if the ball is in magenta's goal (x > 0 side), -1 in cyan's, 0 if in neither."""
    b = sim.model_states()["ball"]
    f = sim.scene.spec.world
    if abs(b.x) > f.length / 2 + 0.11 and abs(b.y) < f.goal_width / 2 and b.z < f.goal_height:
        return 1 if b.x > 0 else -1
    return 0


def run_until(sim, condition, seconds: float, step: float = 0.05) -> bool:
    """Run until ``condition()`` holds (checked every ``step`` s) or ``seconds`` pass; whether it held."""
    end = sim.time + seconds
    while sim.time < end - 1e-9:
        sim.run(seconds=step)
        if condition():
            return True
    return False
