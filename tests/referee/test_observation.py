"""The referee's observation reads the latest ModelStates into plain lists: by slices when the message lists
the robots and then the ball (the simulator's order), by rows otherwise; robots short of the areas are
classified without looking further. Both ways give what the plain loop over every robot gives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch import msgs
from simatch.config.loader import load_scene
from simatch.scene.referee.observation import Observation


def _reference(obs: Observation, msg) -> dict:
    """Every robot's numbers and areas, read row by row (the plain way)."""
    names = list(msg.name)
    P, T = msg.pose.tolist(), msg.twist.tolist()
    out = {"X": [], "Y": [], "VX": [], "VY": [], "pen": [], "goal": []}
    for nm in obs.names:
        r = names.index(nm)
        x, y = P[7 * r], P[7 * r + 1]
        out["X"].append(x)
        out["Y"].append(y)
        out["VX"].append(T[6 * r])
        out["VY"].append(T[6 * r + 1])
        side = 1 if x > 0 else -1
        out["pen"].append(side if abs(x) >= obs._pen_x and abs(y) <= obs._pen_y else 0)
        out["goal"].append(side if abs(x) >= obs._goal_x and abs(y) <= obs._goal_y else 0)
    b = names.index("ball")
    out["ball"] = (P[7 * b], P[7 * b + 1], P[7 * b + 2], T[6 * b], T[6 * b + 1], T[6 * b + 2], T[6 * b + 3])
    return out


@pytest.mark.parametrize("shuffled", [False, True])
def test_refresh_equals_the_plain_reading(shuffled):
    scene = load_scene("msl_5v5")
    rng = np.random.default_rng(5 + shuffled)
    obs = Observation(scene, 0.26)
    names = obs.names + ["ball"]
    order = rng.permutation(len(names)) if shuffled else np.arange(len(names))
    held = obs.X  # a rule may hold the lists: they are filled in place
    for case in range(400):
        m = len(names)
        pose = rng.uniform(-12, 12, 7 * m).astype(np.float32)
        if case % 4 == 0:  # robots on the areas' lines and corners, and at signed zeros
            for r in range(m):
                pose[7 * r] = rng.choice([obs._pen_x, -obs._pen_x, obs._goal_x, -obs._goal_x, -0.0, 0.0, math.nan])
                pose[7 * r + 1] = rng.choice([obs._pen_y, -obs._pen_y, obs._goal_y, -obs._goal_y, 0.0])
        twist = rng.normal(0, 2, 6 * m).astype(np.float32)
        msg = msgs.new(msgs.ModelStates, stamp=case * 0.025, step=case * 5, name=[names[i] for i in order])
        msg.pose, msg.twist = pose, twist
        obs.set_message(msg)
        obs.refresh()
        want = _reference(obs, msg)
        got = {"X": obs.X, "Y": obs.Y, "VX": obs.VX, "VY": obs.VY, "pen": obs.penalty_area, "goal": obs.goal_area}
        for key, values in got.items():
            assert np.array_equal(np.array(values), np.array(want[key]), equal_nan=True), (case, key)
        ball = (obs.bx, obs.by, obs.bz, obs.bvx, obs.bvy, obs.bvz, obs.bwx)
        assert np.array_equal(np.array(ball), np.array(want["ball"]), equal_nan=True)
        assert obs.X is held
    assert obs._in_order == (not shuffled)


def test_the_ball_over_a_line_is_judged_on_plain_floats_as_numpy_judges_float32():
    """The referee reads the ball's float32 position as plain floats at every step and compares it with the
    limits rounded to float32: the same test as NumPy's comparison of a float32 with the float64 limit."""
    rng = np.random.default_rng(5)
    for limit in (11.0 + 0.11, 7.0 + 0.125 + 0.11, 9.08, 6.0 + 1.0 / 3.0):
        lim32 = msgs.f32(limit)
        near = np.nextafter(np.float32(limit), np.float32(np.inf)) + rng.normal(0.0, 1e-6, 2000).astype(np.float32)
        for v in np.concatenate((near, -near, np.float32([limit, -limit, lim32, -lim32]))).astype(np.float32):
            x = v.item()
            assert (v > limit) == (x > lim32) and (v < -limit) == (x < -lim32)
