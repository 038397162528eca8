"""Runs of the encirclement scene through the Python API, closed after each test."""

from __future__ import annotations

import pytest

import simatch

IDLE = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none"}


@pytest.fixture
def encirclement():
    """``make(seed=0, **overrides)``: a Simulation of encirclement_9v7 (both teams idle with ``idle=True``)."""
    sims = []

    def make(seed: int = 0, idle: bool = False, **overrides):
        over = dict(IDLE) if idle else {}
        over.update(overrides)
        sim = simatch.Simulation("encirclement_9v7", seed=seed, overrides=over)
        sims.append(sim)
        return sim

    yield make
    for sim in sims:
        sim.close()


def target_positions(sim, team: str = "magenta") -> dict[str, tuple[float, float]]:
    states = sim.model_states()
    return {n: (s.x, s.y) for n, s in states.items() if n.startswith(team + "/")}


def park_targets(sim, keep: tuple[str, ...] = ()) -> None:
    """Targets not in ``keep`` to the far -x end of the arena, in a row, out of the way."""
    y = -5.0
    for name in target_positions(sim):
        if name not in keep:
            sim.set_model_state(name, x=-5.0, y=y, yaw=0.0, vx=0.0, vy=0.0, wz=0.0)
            y += 1.5
