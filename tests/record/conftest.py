"""Recordings made by real runs (real MuJoCo, real bus, real files), shared by the recording tests."""

from __future__ import annotations

import pytest

import simatch
from simatch.record import Recorder

#: these recordings drive the match through the teams' coaches: no referee
COACHED = {"judge.kind": "none"}
NOISY = {**COACHED, "perception.position_noise": 0.05, "perception.ball_dropout": 0.2}


def play_a_little(sim) -> None:
    """Two simulated seconds of 5v5 with every kind of operator command (API calls, coach commands)."""
    for coach in sim.coaches.values():
        coach.start_play()
    sim.set_model_state("ball", x=-2.9, y=1.0, z=0.11, vx=-1.0, vy=0.0)  # rolls into cyan/2 (at -3.5, 1)
    sim.set_model_state("magenta/3", x=0.0, y=-3.0, yaw=1.0)
    sim.run(seconds=0.6)
    sim.take_control("cyan/2")
    sim.send_vel("cyan/2", 1.5, 0.2, 1.0)
    sim.apply_wrench("ball", force=(4.0, 0.0, 0.0), duration=0.05)
    sim.run(seconds=0.6)
    sim.send_action("cyan/2", dribble=True, kick=3.0)
    sim.coaches["magenta"].stop_play()
    sim.run(seconds=0.4)
    sim.release_control("cyan/2")
    sim.coaches["magenta"].start_play()
    sim.run(seconds=0.4)


def record_run(path, seed: int = 4, overrides=None, script=play_a_little) -> str:
    """Record ``script`` on msl_5v5 into ``path``; returns the final state digest."""
    with simatch.Simulation("msl_5v5", seed=seed, overrides=dict(NOISY if overrides is None else overrides)) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            script(sim)
        return sim.state_digest()


@pytest.fixture(scope="package")
def recording(tmp_path_factory):
    """(path, final digest) of a 2 s recorded run with operator commands and noisy perception."""
    path = tmp_path_factory.mktemp("rec") / "match.mcap"
    digest = record_run(path)
    return path, digest
