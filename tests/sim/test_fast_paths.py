"""The simulator's per-step fast paths give exactly what the general ones give: the ModelStates message's
float32 arrays (one compiled call instead of the float64 states rounded) and the robots touching the ball
(the contact list left unread while no robot geom's bounding sphere reaches the ball's)."""

from __future__ import annotations

import numpy as np
import pytest

import simatch
from simatch.config.loader import shipped_scenes
from simatch.sim.kernels import ball_apart


def _touches_from_contacts(sim) -> list[int]:
    """The robots in contact with the ball, read from the whole contact list (the general way)."""
    d, bg = sim.d, sim.ix.ball_geom
    found = set()
    for a, b in d.contact.geom[: d.ncon].tolist():
        other = b if a == bg else a if b == bg else -1
        if other >= 0 and sim._geom_robot_list[other] >= 0:
            found.add(sim._geom_robot_list[other])
    return sorted(found)


@pytest.mark.parametrize("name", sorted(shipped_scenes()))
def test_model_states_message_arrays_are_the_exact_states_in_float32(name):
    # every shipped world (a world with other bodies than ground robots and the ball must keep this true)
    with simatch.Simulation(name, seed=4) as run:
        sim = run.simulator
        for _ in range(3):
            names, pose, twist = sim.model_state_arrays()
            pose32, twist32 = sim.model_state_arrays32()
            assert pose32.dtype == twist32.dtype == np.float32
            assert pose32.tobytes() == pose.astype(np.float32).ravel().tobytes()
            assert twist32.tobytes() == twist.astype(np.float32).ravel().tobytes()
            assert len(names) * 7 == pose32.size and len(names) * 6 == twist32.size
            run.run(seconds=0.5, until_done=False)


def test_model_states_message_carries_the_float32_arrays():
    with simatch.Simulation("msl_5v5", seed=2) as run:
        heard = []

        def check(msg):  # at delivery, the world is at the message's step
            _, pose, twist = run.simulator.model_state_arrays()
            assert msg.pose.tobytes() == pose.astype(np.float32).ravel().tobytes()
            assert msg.twist.tobytes() == twist.astype(np.float32).ravel().tobytes()
            heard.append(msg)

        run.bus.subscribe("model_states", None, check)
        run.run(seconds=0.05, until_done=False)
        assert len(heard) == 10
        assert heard[-2].pose is not heard[-1].pose  # a fresh array in every message (subscribers may keep them)


def test_ball_touches_equal_the_contact_list_near_and_far_from_the_ball():
    with simatch.Simulation("msl_5v5", seed=1) as run:
        sim = run.simulator
        apart = near = touched = 0

        def steps(k):
            nonlocal apart, near, touched
            for _ in range(k):
                run.run(seconds=sim.dt, until_done=False)
                assert sim.ball_touches() == _touches_from_contacts(sim)
                if ball_apart(sim._geom_xpos, sim._touch_geoms, sim._touch_bound2, sim.ix.ball_geom):
                    apart += 1
                else:
                    near += 1
                    touched += bool(sim.ball_touches())

        steps(400)  # the kick-off: the ball far from most robots
        for name in ("cyan/2", "magenta/3"):  # then dropped on a robot, against its side and in its mouth
            st = run.model_states()[name]
            run.set_model_state("ball", x=st.x, y=st.y + 0.3, z=0.11, vx=0.0, vy=-1.0, vz=0.0)
            steps(40)
        assert apart > 100 and near > 20 and touched > 5  # both paths taken, touches seen
