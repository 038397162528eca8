"""Worlds with drones for the aerial tests: real MuJoCo through the Python API, closed after each test."""

from __future__ import annotations

import pytest

import simatch
from simatch.config.loader import scene_from_text
from tests.distributed.conftest import procs  # noqa: F401  (real processes, none outliving a test: test_distributed)
from tests.web.conftest import live, open_page  # noqa: F401  (the web UI's fixtures, for test_web)

ARENA = """
name = "{name}"
[physics]
gravity = {gravity}
[world]
kind = "arena"
length = {size}
width = {size}
walls = {walls}
wall_height = 3.0
obstacles = [{obstacles}]
[ball]
position = [{corner}, {corner}]
[teams.cyan]
model = "quadrotor"
model_params = {{ {params} }}
strategy = "none"
start = [{start}]
"""


def drone_scene(
    start=((0.0, 0.0, 0.0),),
    params: str = "start_altitude = 1.0",
    size: float = 20.0,
    walls: bool = True,
    obstacles: str = "",
    gravity: float = 9.8,
    name: str = "drones",
):
    """A walled arena (3 m walls) with drones of team cyan, no strategy (the test flies them)."""
    text = ARENA.format(
        name=name,
        gravity=gravity,
        size=size,
        walls="true" if walls else "false",
        obstacles=obstacles,
        corner=-size / 2 + 0.5,
        params=params,
        start=", ".join(f"[{x}, {y}, {yaw}]" for x, y, yaw in start),
    )
    return scene_from_text(text, f"<test {name}>")


@pytest.fixture
def drones():
    """``make(**drone_scene args)``: a Simulation of `drone_scene`, every drone under the test's control."""
    sims = []

    def make(seed: int = 0, **kw):
        sim = simatch.Simulation(drone_scene(**kw), seed=seed)
        sims.append(sim)
        for name in sim.simulator.robot_names:
            sim.take_control(name)
        return sim

    yield make
    for sim in sims:
        sim.close()


def track(sim, name: str, seconds: float) -> list:
    """Step ``seconds`` and return the drone's ModelStateView after every physics step."""
    out = []
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        out.append(sim.model_states()[name])
    return out
