"""Deterministic by default: the same scene and seed give the same run, bit for bit."""

from __future__ import annotations

import simatch


def _digest(seed, **overrides):
    with simatch.Simulation("msl_5v5", seed=seed, overrides=overrides) as sim:
        for coach in sim.coaches.values():
            coach.start_play()
        sim.set_model_state("ball", x=0.3, y=-0.2, z=0.11, vx=-2.0, vy=1.0)
        for name in ("cyan/2", "magenta/3"):  # away from their start poses: they drive back
            sim.set_model_state(name, x=0.0, y=3.0 if name == "cyan/2" else -3.0, yaw=1.0)
        sim.run(seconds=3.0)
        return sim.state_digest()


def test_same_seed_same_digest():
    assert _digest(7) == _digest(7)


def test_noise_follows_the_seed():
    noisy = {"perception.position_noise": 0.2, "perception.ball_dropout": 0.3}
    assert _digest(3, **noisy) == _digest(3, **noisy)
    assert _digest(3, **noisy) != _digest(4, **noisy)
