"""The nubot team obeys every kind of game command: STOP, PARK, the coach's TEST commands; and its roles
are stable while it plays."""

from __future__ import annotations

import math
from collections import Counter

from simatch.msgs.game_commands import MatchMode as M
from simatch.msgs.game_commands import TestMode as T
from simatch.strategy.roles import Role
from tests.strategy.helpers import BallWatch, bench_all_but, command, run_until, scenario, start


def test_stop_stands_still_and_park_lines_up_beside_the_field():
    sim = scenario(cyan="nubot", magenta="nubot")
    sim.step()
    start(sim)
    sim.run(seconds=3.0)
    command(sim, "cyan", M.STOPROBOT)
    sim.run(seconds=1.5)  # braking from full speed takes about a second
    ms = sim.model_states()
    assert all(math.hypot(ms[n].vx, ms[n].vy) < 0.05 for n in sim.simulator.robot_names)
    command(sim, "cyan", M.PARKINGROBOT)
    sim.run(seconds=12.0)
    ms = sim.model_states()
    for n in sim.simulator.robot_names:
        side = -1 if n.startswith("cyan") else 1  # each team parks on its right, in its own half
        assert abs(ms[n].y) > 7.0 and side * ms[n].y > 0 and side * ms[n].x > 0, (n, ms[n].x, ms[n].y)
        assert abs(math.remainder(ms[n].yaw - (math.pi / 2 if side < 0 else -math.pi / 2), 2 * math.pi)) < 0.2
    sim.close()


def test_move_to_a_point_with_and_without_avoidance():
    for mode in (T.MOVE_NOBALL_NOAVOID, T.MOVE_NOBALL_AVOID):
        sim = scenario()
        sim.step()
        sim.coaches["cyan"].send(M.TEST, test_mode=int(mode), id_a=3, point_a_x=4.0, point_a_y=-3.0, angle_a=1.0)
        others = {n: (sim.model_states()[n].x, sim.model_states()[n].y) for n in ("cyan/2", "cyan/4")}
        sim.run(seconds=6.0)
        st = sim.model_states()["cyan/3"]
        assert math.hypot(st.x - 4.0, st.y + 3.0) < 0.1 and abs(math.remainder(st.yaw - 1.0, 2 * math.pi)) < 0.1
        for n, (x, y) in others.items():  # robots not named stand still
            assert math.hypot(sim.model_states()[n].x - x, sim.model_states()[n].y - y) < 0.05
        sim.close()


def test_catch_then_shoot_at_a_target():
    sim = scenario()
    bench_all_but(sim, ["cyan/2"])
    sim.set_model_state("ball", x=-3.0, y=2.0, z=0.11)
    watch = BallWatch(sim)
    sim.step()
    sim.coaches["cyan"].send(M.TEST, test_mode=int(T.CATCH_BALL), id_a=2)
    assert run_until(sim, lambda: watch.held_by("cyan/2"), 6.0)
    sim.run(seconds=1.0)
    assert sim.simulator.ball.holder == sim.simulator.index_of("cyan/2")  # and keeps it
    sim.coaches["cyan"].send(
        M.TEST, test_mode=int(T.SHOOT_BALL), id_a=2, point_a_x=-3.0, point_a_y=-5.0, kick_force=6.0
    )
    assert run_until(sim, lambda: bool(watch.kicks), 4.0)
    b = sim.model_states()["ball"]
    me = sim.model_states()["cyan/2"]
    heading = math.atan2(b.vy, b.vx)
    aim = math.atan2(-5.0 - me.y, -3.0 - me.x)
    assert abs(math.remainder(heading - aim, 2 * math.pi)) < 0.15
    assert 5.0 < math.hypot(b.vx, b.vy) < 7.5
    sim.close()


def test_pass_from_a_to_b():
    sim = scenario()
    bench_all_but(sim, ["cyan/2", "cyan/3"])
    sim.set_model_state("ball", x=-4.0, y=0.0, z=0.11)
    watch = BallWatch(sim)
    sim.step()
    sim.coaches["cyan"].send(
        M.TEST, test_mode=int(T.PASS_BALL), id_a=2, id_b=3, point_a_x=-4.0, point_a_y=-1.0, point_b_x=0.0, point_b_y=3.0
    )
    assert run_until(sim, lambda: watch.held_by("cyan/3"), 15.0), watch.holders
    assert watch.kicks and watch.kicks[0][1] == "cyan/2"
    sim.close()


def test_roles_are_stable_in_play():
    """Over a minute of play roles hardly flicker (a role taken and given back within half a second: at
    most once per robot and minute; without hysteresis it happens about ten times as often), the team
    always has exactly one goalkeeper and at most one active robot besides a pass receiver."""
    sim = scenario(cyan="nubot", magenta="nubot", seed=3)
    sim.step()
    command(sim, "cyan", M.OUR_KICKOFF)
    sim.run(seconds=6.0)
    start(sim)
    history = {n: [] for n in sim.robot_nodes}
    flickers = Counter()
    for _ in range(int(60.0 / 0.025)):
        sim.run(seconds=0.025)
        for team in ("cyan", "magenta"):
            roles = {n: node.strategy.role for n, node in sim.robot_nodes.items() if n.startswith(team)}
            assert list(roles.values()).count(Role.GOALIE) == 1
            assert sum(r in (Role.ACTIVE, Role.CATCHOFPASS) for r in roles.values()) <= 2
        for n, node in sim.robot_nodes.items():
            h = history[n]
            role = node.strategy.role
            if not h or h[-1][1] != role:
                h.append((sim.time, role))
                if len(h) >= 3 and h[-1][1] == h[-3][1] and h[-1][0] - h[-2][0] < 0.5:
                    flickers[n] += 1
    changes = sum(len(h) - 1 for h in history.values())
    assert sum(flickers.values()) <= len(history) - 2, flickers
    assert changes < 60 * 10 / 3, changes  # on average a role lasts several seconds
    sim.close()


def test_circle_test_runs_round_the_point():
    """The coach's CIRCLE_TEST: the robot named drives round point A at the radius to point B, without
    a strategy error."""
    sim = scenario()
    bench_all_but(sim, ["cyan/3"])
    sim.set_model_state("cyan/3", x=2.0, y=0.0, yaw=0.0)
    sim.step()
    sim.coaches["cyan"].send(
        M.TEST, test_mode=int(T.CIRCLE_TEST), id_a=3, point_a_x=0.0, point_a_y=0.0, point_b_x=2.0, point_b_y=0.0
    )
    angles = []
    for _ in range(16):
        sim.run(seconds=0.5)
        st = sim.model_states()["cyan/3"]
        assert abs(math.hypot(st.x, st.y) - 2.0) < 0.5
        angles.append(math.atan2(st.y, st.x))
    assert sim.robot_nodes["cyan/3"].errors == 0
    assert max(angles) - min(angles) > 1.0  # it went round
    sim.close()
