"""The referee's ball touches: the steady hold (the robot that alone held and touched the ball at the last step
still does) is taken in a few assignments instead of the general reading of a ``ball_contacts`` message, with
the same result."""

from __future__ import annotations

import copy

import simatch


def test_the_steady_hold_leaves_the_touches_as_the_general_way_does():
    with simatch.Simulation("msl_5v5", seed=1) as run:
        touches = run.judge.m.touches
        fast = touches.on_contacts
        general = touches._contact
        seen = {"messages": 0, "general": 0}

        def counted(msg, step):
            seen["general"] += 1
            general(msg, step)

        def both(msg):
            # the general way on a copy of the touches as they were (the observation shared: it is read only)
            shadow = copy.deepcopy(touches, {id(touches.obs): touches.obs})
            type(touches)._contact(shadow, msg, int(msg.step))
            fast(msg)
            seen["messages"] += 1
            mine = {k: v for k, v in vars(touches).items() if k not in ("obs", "on_contacts", "_contact")}
            theirs = {k: v for k, v in vars(shadow).items() if k not in ("obs", "on_contacts", "_contact")}
            assert mine == theirs, msg

        touches._contact = counted
        touches.on_contacts = both
        run.run(seconds=40.0, until_done=False)
    steady = seen["messages"] - seen["general"]
    assert steady > 1000 and seen["general"] > 100  # both ways taken, the steady hold most often
