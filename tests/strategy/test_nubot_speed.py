"""The speed work on nubot keeps what robots decide: the helpers rewritten for speed against the plain
versions they replace, the opponents' array shared within a team, and the kernels the benchmark loads
before timing."""

import math
import random
import struct

import numpy as np

import simatch
from simatch.field import FieldGeometry
from simatch.strategy.nubot import ballpath, observation, picture, positions
from simatch.strategy.nubot.avoidance import GROUP_GAP, MAX_TURN, SIDE_HYSTERESIS, TWO_PI, _wrap
from simatch.strategy.nubot.geometry import segment_hits_box
from simatch.strategy.nubot.observation import _array
from simatch.strategy.nubot.positions import Areas
from simatch.strategy.nubot.warm import load_kernels


def test_route_skips_only_boxes_the_way_cannot_cross():
    """route's shortcut (both ends beside a box) never skips a box the full test says the way crosses."""
    rng = random.Random(3)
    boxes = [(-14.0, -10.5, 3.6), (10.5, 14.0, 3.6), (-1.0, 1.0, 0.5)]
    for _ in range(50_000):
        x0, x1, hw = rng.choice(boxes)
        px, tx = (rng.choice([x0, x1]) if rng.random() < 0.2 else rng.uniform(-15, 15) for _ in range(2))
        py, ty = (rng.choice([-hw, hw]) if rng.random() < 0.2 else rng.uniform(-8, 8) for _ in range(2))
        beside = (
            (px <= x0 and tx <= x0) or (px >= x1 and tx >= x1) or (py <= -hw and ty <= -hw) or (py >= hw and ty >= hw)
        )
        assert not (beside and segment_hits_box(px, py, tx, ty, x0, x1, hw)), (px, py, tx, ty, x0, x1, hw)


def test_route_goes_round_a_box_in_the_way():
    areas = Areas(FieldGeometry(), 0.4)
    x0, x1, hw = areas.opp_pa
    sx, sy = areas.route(x0 - 2.0, 0.3, x1 + 1.0, 0.0, [areas.opp_pa])
    assert (sx, sy) != (x1 + 1.0, 0.0) and abs(sy) > hw
    assert areas.route(0.0, 0.0, 3.0, 1.0, [areas.own_pa, areas.opp_pa]) == (3.0, 1.0)


def test_small_arrays_hold_the_values_of_np_array():
    rows = [(1.5, -2.0, 0.1, 0.0), (math.pi, 1e-300, -0.0, 7.0)]
    a = _array(rows, 4)
    assert a.shape == (2, 4) and a.dtype == np.float64 and a.flags.c_contiguous
    assert np.array_equal(a, np.array(rows, dtype=float))
    assert _array([], 5).shape == (0, 5)
    assert np.array_equal(_array([(1.0, 2.0, 0.0, 0.0, 3)], 5), np.array([(1.0, 2.0, 0.0, 0.0, 3)], dtype=float))


def _kernels():
    return {
        "intercepts": ballpath._intercepts,
        "team_intercepts": ballpath._team_intercepts,
        "score_spots": positions._score_spots,
        "assist_choice": picture._assist_choice,
        "assign": picture._assign_flat,
        "open_slots": picture._open_slots,
    }


def _random_path(rng):
    return ballpath.BallPath(
        rng.uniform(-11, 11),
        rng.uniform(-7, 7),
        rng.choice([0.11, 0.11, rng.uniform(0.11, 2.0)]),
        rng.choice([0.0, rng.uniform(-8, 8)]),
        rng.choice([0.0, rng.uniform(-8, 8)]),
        rng.choice([0.0, 0.0, rng.uniform(-1, 5)]),
        rng.uniform(0.2, 0.8),
        0.11,
        12.3,
        8.3,
    )


def test_team_intercepts_in_one_kernel_equal_the_rows_then_the_intercepts():
    """`team_intercepts` (one kernel) gives, bit for bit, what its two steps give called one by one."""
    rng = random.Random(5)
    for _ in range(3000):
        path = _random_path(rng)
        us = np.array(
            [
                [
                    rng.uniform(-12, 12),
                    rng.uniform(-8, 8),
                    rng.uniform(-3, 3),
                    rng.uniform(-3, 3),
                    k,
                    rng.uniform(-4, 4),
                ]
                for k in range(rng.randint(0, 5))
            ]
        ).reshape(-1, 6)
        opps = np.array(
            [
                [rng.uniform(-12, 12), rng.uniform(-8, 8), rng.uniform(-3, 3), rng.uniform(-3, 3)]
                for _ in range(rng.randint(0, 5))
            ]
        ).reshape(-1, 4)
        bx, by, turn = path.x + rng.uniform(-1, 1), path.y, rng.uniform(0.05, 0.5)
        vmax, acc = rng.uniform(1.0, 4.0), rng.uniform(1.0, 3.0)
        fused = ballpath.team_intercepts(path, us, opps, bx, by, turn, vmax, acc)
        px, py, vx, vy, extra = ballpath._team_rows(us, opps, bx, by, turn)
        plain = ballpath.intercepts(path, px, py, vx, vy, vmax, acc, extra)
        assert fused.tobytes() == plain.tobytes()


def test_assistant_spots_compiled_equal_the_plain_choice():
    """The assistants' spots chosen in one kernel equal the plain choice (NumPy's argsort, Python's hypot) on
    random situations; where equal scores make the order of equals matter the kernel says so (-1) and the
    team takes the plain way."""
    areas = Areas(FieldGeometry(), 0.4)
    cx, cy = positions.spot_grid(areas)
    rng = random.Random(11)
    ties = 0
    for case in range(4000):
        opps = [[rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0] for _ in range(rng.randint(0, 5))]
        if case % 10 == 0:  # symmetric situations, where scores come out equal
            opps, bx, by = [], rng.choice([0.0, 2.0, -4.0]), 0.0
        else:
            bx, by = rng.uniform(-11, 11), rng.uniform(-7, 7)
        prev = None if rng.random() < 0.3 else (rng.uniform(-11, 11), rng.uniform(-7, 7))
        n = rng.choice([1, 2, 12])  # (12: the order of all twelve best counts)
        plain = picture.assist_spots(cx, cy, bx, by, opps, areas.L2, prev, n)
        nx, ny = prev if prev is not None else (math.nan, math.nan)
        out = np.empty((n, 2))
        arr = np.array(opps, dtype=float).reshape(-1, 4)
        k = picture._assist_choice(cx, cy, bx, by, arr, areas.L2, 3.0, 8.5, nx, ny, out)
        if k < 0:
            ties += 1
            continue
        assert [(x, y) for x, y in out[:k].tolist()] == plain
    assert 0 < ties < 1000


def _plain_opponents(ox, oy, ovx, ovy, mates):
    """The rule of `observation._opponents`, plainly: exact positions first, by distance under noise."""
    rows = [(float(x), float(y), float(vx), float(vy)) for x, y, vx, vy in zip(ox, oy, ovx, ovy)]
    exact = [r for r in rows if not any(m[0] == r[0] and m[1] == r[1] for m in mates)]
    if len(rows) - len(exact) >= len(mates) - 1:
        return exact
    near = observation._SAME_ROBOT
    return [r for r in exact if all(abs(m[0] - r[0]) >= near or abs(m[1] - r[1]) >= near for m in mates)]


def test_opponents_are_told_from_team_mates_as_the_plain_rule_says():
    rng = random.Random(2)
    for _ in range(3000):
        mates = [(rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0, k + 1) for k in range(rng.randint(1, 5))]
        others = [(rng.uniform(-11, 11), rng.uniform(-7, 7)) for _ in range(rng.randint(0, 5))]
        seen = [(x, y) for x, y, *_ in mates[1:]] + others
        if rng.random() < 0.5:  # noisy perception: team-mates a few centimetres off
            seen = [(x + rng.uniform(-0.05, 0.05), y + rng.uniform(-0.05, 0.05)) for x, y in seen]
        rng.shuffle(seen)
        f32 = np.float32
        ox = np.array([x for x, _ in seen], dtype=f32)
        oy = np.array([y for _, y in seen], dtype=f32)
        ovx = np.array([rng.uniform(-3, 3) for _ in seen], dtype=f32)
        ovy = np.array([rng.uniform(-3, 3) for _ in seen], dtype=f32)
        m = np.array(mates, dtype=float).reshape(-1, 5)
        m[:, :2] = m[:, :2].astype(f32)  # as the team list's float32 numbers
        out = np.full((len(seen), 4), np.nan)
        bx, by = rng.uniform(-11, 11), rng.uniform(-7, 7)
        if rng.random() < 0.2:  # the ball at a robot
            bx, by = float(m[0, 0]), float(m[0, 1])
        k, near, near_d, opp_d = observation._opponents(ox, oy, ovx, ovy, m, out, bx, by)
        opps = _plain_opponents(ox, oy, ovx, ovy, m.tolist())
        assert out[:k].tolist() == [list(r) for r in opps]
        # the nearest team-mate (the first of equals) and opponent, by Python's own hypot
        dists = [math.hypot(x - bx, y - by) for x, y in m[:, :2].tolist()]
        assert (near, near_d) == min(enumerate(dists), key=lambda e: e[1])
        assert opp_d == min((math.hypot(x - bx, y - by) for x, y, _, _ in opps), default=math.inf)


def test_load_kernels_loads_what_open_play_calls():
    """After `load_kernels`, a match into open play needs no kernel signature it has not loaded yet (the
    benchmark relies on this: nothing compiles or loads while it measures)."""
    load_kernels()
    before = {k: set(map(str, f.signatures)) for k, f in _kernels().items()}
    assert all(before.values())
    with simatch.Simulation("msl_5v5", seed=1) as sim:
        sim.run(seconds=14.0, until_done=False)
        phases = {n.strategy.picture.phase for n in sim.robot_nodes.values() if n.strategy.picture is not None}
        evaluated = sum({id(n.strategy.shared): n.strategy.shared.evaluated for n in sim.robot_nodes.values()}.values())
    after = {k: set(map(str, f.signatures)) for k, f in _kernels().items()}
    assert evaluated > 0 and 4 in phases  # open play (gameflow.Phase.PLAY) was reached
    assert after == before


def test_a_robot_alone_decides_as_in_its_team():
    """Robots that each compute their own team picture (one robot per process in a distributed run) play
    the very same match as a team sharing one picture per tick: the sharing is only a cache."""
    from simatch.config.loader import load_scene

    lone = "simatch.strategy.nubot:NubotRobot"
    digests = []
    for overrides in ({}, {"teams.cyan.strategy": lone, "teams.magenta.strategy": lone}):
        with simatch.Simulation(load_scene("msl_5v5", overrides), seed=3) as sim:
            sim.run(seconds=12.0, until_done=False)
            shared = {id(n.strategy.shared) for n in sim.robot_nodes.values()}
            digests.append((len(shared), sim.state_digest()))
    (team_pictures, team_digest), (lone_pictures, lone_digest) = digests
    assert (team_pictures, lone_pictures) == (2, 10)
    assert team_digest == lone_digest


def test_a_rounded_move_sends_the_messages_of_the_same_command():
    """RobotNode.publish_move builds, from a RoundedMove's numbers, the very messages (byte for byte)
    that publish builds from the Command it stands for."""
    from simatch import msgs
    from simatch.strategy.base import Command, PassIntent, RoundedMove

    with simatch.Simulation("msl_5v5", seed=1) as sim:
        sim.run(seconds=0.5, until_done=False)
        node = sim.robot_nodes[next(iter(sim.robot_nodes))]
        got = []
        subs = [
            sim.bus.subscribe(p.topic, p.msgtype, got.append) for p in (node.pub_vel, node.pub_action, node.pub_info)
        ]
        rng = random.Random(5)
        special = [0.0, -0.0, 1e-42, -3.0e38, 1.0 / 3.0, 7.000000476837158]
        for k in range(3000):
            vx, vy, w, x, y = (rng.choice(special) if rng.random() < 0.1 else rng.uniform(-8.0, 8.0) for _ in range(5))
            role, action = rng.randrange(11), rng.randrange(22)
            user = (float(rng.random() < 0.5), rng.uniform(0.0, 60.0)) if k % 7 else ()
            intent = PassIntent(3, x, y, vy, vx, kicked=k % 2 == 0) if k % 5 == 0 else None
            cmd = Command(vx=vx, vy=vy, w=w, role=role, action=action, intent=(x, y), user=user)
            cmd.pass_intent = intent
            node.publish(0.025 * k, k, cmd, vx, vy, w)
            plain = [msgs.encode(m) for m in got]
            got.clear()
            move = RoundedMove(*msgs.f32s(vx, vy, w), role, action, msgs.f32s(x, y), user)
            move.pass_intent = intent
            node.publish_move(0.025 * k, k, move)
            assert [msgs.encode(m) for m in got] == plain, (vx, vy, w, x, y, role, action, user)
            got.clear()
        for s in subs:
            s.close()


def test_the_motion_row_holds_the_command_rounded_as_the_messages_round_it():
    """Motion.go's kernel writes the body velocity and the target asked for, rounded to float32, into the
    motion's row: the numbers msgs.f32s gives of what it returns."""
    from simatch import msgs
    from simatch.strategy.nubot.observation import Observation, TeamView

    with simatch.Simulation("msl_5v5", seed=1) as sim:
        sim.run(seconds=3.0, until_done=False)
        rng = random.Random(9)
        for node in sim.robot_nodes.values():
            robot = node.strategy
            obs = Observation(node.world, TeamView())
            motion, areas = robot.motion, robot.areas
            for _ in range(400):
                tx, ty = rng.uniform(-13.0, 13.0), rng.uniform(-9.0, 9.0)
                face = rng.uniform(-4.0, 4.0) if rng.random() < 0.8 else None
                fence = (obs.bx, obs.by, rng.uniform(0.5, 3.0)) if rng.random() < 0.3 else None
                boxes = areas.forbidden(rng.random() < 0.5) if rng.random() < 0.7 else ()
                vx, vy, w = motion.go(
                    obs,
                    tx,
                    ty,
                    face,
                    rng.uniform(0.5, 4.0),
                    rng.uniform(1.0, 6.0),
                    avoid=rng.random() < 0.8,
                    ball_obstacle=rng.random() < 0.5,
                    boxes=boxes,
                    fence=fence,
                )
                assert motion.row.tolist() == list(msgs.f32s(vx, vy, w, tx, ty))


def test_assign_in_one_array_equals_the_rows_then_the_kernel():
    """`assign` hands the robots' and the slots' rows to the kernel in one array (`_assign_flat`): the same
    assignment as `_assign` of the two arrays made apart, on random teams, slots and circles."""

    class _Robot:
        def __init__(self, rid, x, y, role, role_time):
            self.id, self.x, self.y, self.role, self.role_time = rid, x, y, role, role_time

    rng = random.Random(11)
    for _ in range(3000):
        n, m = rng.randint(1, 6), rng.randint(1, 7)
        robots = [
            _Robot(k + 1, rng.uniform(-11, 11), rng.uniform(-7, 7), rng.choice([-1, 2, 3, 4, 5]), rng.uniform(0, 1.2))
            for k in range(n)
        ]
        slots = [(rng.choice([2, 3, 4, 5]), rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0) for _ in range(m)]
        if rng.random() < 0.2:  # equal costs: the first best assignment wins in both
            slots = [slots[0]] * m
        hysteresis = rng.choice([0.5, 1.0, 50.0])
        around = (rng.uniform(-5, 5), rng.uniform(-3, 3), rng.uniform(0.5, 3.0)) if rng.random() < 0.4 else None
        kept = slots[:n]
        rows = _array(
            [
                (r.x, r.y, r.role, hysteresis + (picture.NEW_ROLE_HOLD if r.role_time < picture.MIN_ROLE_TIME else 0.0))
                for r in robots
            ],
            4,
        )
        cx, cy, cr = around if around is not None else (0.0, 0.0, -1.0)
        best = picture._assign(rows, _array([(s[1], s[2], s[0]) for s in kept], 3), cx, cy, cr)
        want = {robots[i].id: int(best[i]) for i in range(min(n, len(kept)))}
        assert picture.assign(robots, slots, hysteresis, around) == want


def test_open_play_slots_compiled_equal_the_plain_way():
    """`_open_slots` (the roles' points, kept inside the field, spread, assigned: one kernel over the team
    view's table) gives the robots the roles and places `open_slots` gives them, bit for bit, on random
    teams, balls, opponents and receiving spots (near the goal's middle, on top of each other, far apart)."""

    class _Robot:
        def __init__(self, rid, x, y, role, role_time, row):
            self.id, self.x, self.y, self.role, self.role_time, self.row = rid, x, y, role, role_time, row

    areas = Areas(FieldGeometry(), 0.4)
    rng = random.Random(21)
    for _ in range(6000):
        team = [
            _Robot(
                k + 1,
                rng.uniform(-12, 12),
                rng.uniform(-8, 8),
                rng.choice([-1, 1, 2, 3, 4]),
                rng.choice([1e9, rng.uniform(0.0, 1.2)]),
                k,
            )
            for k in range(rng.randint(1, 7))
        ]
        rest = [r for r in team if rng.random() < 0.8] or team[:1]
        table = np.array([(r.x, r.y, 0.0, 0.0, r.id, 0.0, r.role, r.role_time) for r in team])
        attacking = rng.random() < 0.5
        bx, by = rng.uniform(-12.5, 12.5), rng.uniform(-8.5, 8.5)
        if rng.random() < 0.1:
            bx, by = -areas.L2 + rng.choice([0.0, 1e-7]), 0.0  # at our goal's middle
        opps = np.array(
            [(rng.uniform(-12, 12), rng.uniform(-8, 8), 0.0, 0.0) for _ in range(rng.randint(0, 6))]
        ).reshape(-1, 4)
        spots = [(rng.uniform(-10, 10), rng.uniform(-6, 6)) for _ in range(rng.randint(1, 2))]
        if rng.random() < 0.3:
            spots = [(bx + rng.uniform(-0.5, 0.5), by)] * len(spots)  # slots on top of each other: spread
        hysteresis = rng.choice([0.5, 1.0])
        plain = picture.open_slots(
            areas,
            rest,
            attacking,
            spots if attacking else [positions.outlet_point(areas, bx, by)],
            opps.tolist(),
            bx,
            by,
            hysteresis,
        )
        bits = sum(1 << r.row for r in rest)
        out = np.empty((len(rest), 4))
        assist = np.array(spots) if attacking else picture._NO_SPOTS
        k = picture._open_slots(table, bits, len(rest), attacking, assist, opps, bx, by, areas.geo, hysteresis, out)
        compiled = [(rest[i].id, int(role), x, y) for i, (_, role, x, y) in enumerate(out[:k].tolist())]
        assert repr(compiled) == repr([(rid, int(role), x, y) for rid, role, x, y in plain])


def test_a_team_mate_shares_the_opponents_only_when_they_are_the_same_bit_for_bit():
    """`_same_opponents` says a team-mate's rows are this robot's opponents exactly when `_opponents` would
    write those very rows (bit for bit, in order: -0.0 is not 0.0, a NaN never matches), with the same
    nearest team-mate as `_opponents` (and, when shared, the same nearest opponent's distance)."""
    rng = random.Random(21)
    f32 = np.float32
    shared = differ = 0
    for case in range(4000):
        mates = [(rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0, k + 1) for k in range(rng.randint(1, 5))]
        opps = [(rng.uniform(-11, 11), rng.uniform(-7, 7), rng.uniform(-3, 3), rng.uniform(-3, 3)) for _ in range(5)]
        opps = opps[: rng.randint(0, 5)]
        m = np.array(mates, dtype=float).reshape(-1, 5)
        m[:, :2] = m[:, :2].astype(f32)
        bx, by = rng.uniform(-11, 11), rng.uniform(-7, 7)

        def seen(observer, opps=opps, m=m, case=case):
            # the other team-mates and the opponents, in the order perception lists them
            rows = [(x, y, 0.0, 0.0) for j, (x, y) in enumerate(m[:, :2].tolist()) if j != observer] + list(opps)
            if case % 3 == 0:
                rng.shuffle(rows)  # (the opponents' order too: the rows then differ)
            return [np.array([r[i] for r in rows], dtype=f32) for i in range(4)]

        first = seen(0)
        buf = np.empty((len(first[0]), 4))
        k = observation._opponents(*first, m, buf, bx, by)[0]
        prev = buf[:k]
        other = seen(min(1, len(mates) - 1))
        change = rng.random()
        if change < 0.15 and len(other[0]):  # one number differs (a sign of zero, a NaN, a last bit)
            j, i = rng.randrange(len(other[0])), rng.randrange(4)
            a = other[i]
            a[j] = rng.choice([-0.0 if a[j] == 0.0 else 0.0, np.nan, np.nextafter(a[j], f32(np.inf))])
        elif change < 0.2:
            prev = prev.copy()
            if len(prev):
                prev[rng.randrange(len(prev)), rng.randrange(4)] = rng.choice([-0.0, np.nan])
        out = np.empty((len(other[0]), 4))
        want = observation._opponents(*other, m, out, bx, by)
        got = observation._same_opponents(*other, m, prev, bx, by)
        assert observation._same_rows(*other, m, prev) == got[0]
        same = want[0] == len(prev) and out[: want[0]].tobytes() == prev.tobytes() and not np.isnan(prev).any()
        assert (got[0] == len(prev)) == same and got[0] in (len(prev), -1)
        assert got[1:3] == want[1:3]  # (the nearest team-mate; the opponents' distance only when shared)
        assert not same or got[3] == want[3]
        shared += same
        differ += not same
    assert shared > 1000 and differ > 1000


def _packed_go_case(rng, motion, mates, opps):
    face = rng.uniform(-4.0, 4.0) if rng.random() < 0.8 else math.nan
    fence = (rng.uniform(-11, 11), rng.uniform(-7, 7), rng.uniform(0.5, 3.0)) if rng.random() < 0.3 else (math.nan,) * 3
    me = mates[rng.randrange(len(mates))]
    return (
        me[0],
        me[1],
        rng.uniform(-4.0, 4.0),
        rng.uniform(-3, 3),
        rng.uniform(-3, 3),
        int(me[4]),
        rng.uniform(-13.0, 13.0),
        rng.uniform(-9.0, 9.0),
        face,
        rng.uniform(0.5, 4.0),
        rng.uniform(1.0, 6.0),
        rng.random() < 0.8,
        rng.choice([0.0, motion.ball_clearance, 0.9]),
        rng.choice([0.0, 0.0, rng.uniform(0.0, 2.0)]),
        rng.choice([0.0, rng.uniform(-1.0, 1.0)]),
        rng.choice([0.0, rng.uniform(-1.0, 1.0)]),
        rng.uniform(1.0, 4.0),
        rng.random() < 0.7,
        rng.random() < 0.3,
        *fence,
        rng.choice([math.nan, -0.15, rng.uniform(-3.0, 3.0)]),
        rng.uniform(-11, 11),
        rng.uniform(-7, 7),
        rng.choice([-1, 0, 1]),
    )


def test_motion_go_in_one_array_equals_the_kernel_of_every_argument():
    """`Motion.go` calls `_go_packed` (its numbers in one array, without the dispatcher): the same results,
    avoidance side and float32 row as `_go` given each number as an argument, on random situations."""
    import struct

    from simatch.strategy.nubot import motion as motion_mod
    from simatch.strategy.nubot.params import NubotParams, plain

    field = FieldGeometry()
    params = plain(NubotParams())
    areas = Areas(field, params.robot_radius + 0.15)
    mo = motion_mod.Motion(params, 0.025, field, areas)
    rng = random.Random(17)
    box_sets = [motion_mod._NO_BOXES, areas.box_array(areas.forbidden(False)), areas.box_array(areas.forbidden(True))]
    for _ in range(4000):
        mates = np.array(
            [
                (rng.uniform(-11, 11), rng.uniform(-7, 7), rng.uniform(-2, 2), rng.uniform(-2, 2), k + 1, 0.0, 2.0, 1.0)
                for k in range(rng.randint(1, 5))
            ]
        )
        opps = np.array(
            [(rng.uniform(-11, 11), rng.uniform(-7, 7), rng.uniform(-2, 2), rng.uniform(-2, 2)) for _ in range(5)]
        )[: rng.randint(0, 5)].copy()
        boxes = rng.choice(box_sets)
        a = _packed_go_case(rng, mo, mates.tolist(), opps)
        row = np.zeros(5, dtype=np.float32)
        want = motion_mod._go(*a[:19], boxes, *a[19:23], opps, mates, *a[23:], mo.consts, row)
        struct.pack_into(f"{len(a)}d", mo._args_buf, motion_mod._ARGS_AT, *a)
        got = mo._go(mo.args, boxes, opps, mates, mo.row)
        assert struct.pack("6d", *got) == struct.pack("6d", *want) and got[3] == want[3], a
        assert mo.row.tobytes() == row.tobytes()


def _plain_sub_target(px, py, tx, ty, opps, mates, me_id, ball_x, ball_y, ball_clear, clear, look, prefer_side):
    """The rule of avoidance.sub_target in plain Python over lists (the same float operations; ``** 2`` as the
    product numba makes of it): the reference its compiled storage is held to."""
    length = math.sqrt((tx - px) * (tx - px) + (ty - py) * (ty - py))
    if length < 1e-6:
        return tx, ty, 0
    ux, uy = (tx - px) / length, (ty - py) / length
    obst = [(o[0] + look * o[2], o[1] + look * o[3], clear) for o in opps.tolist()]
    obst += [(m[0] + look * m[2], m[1] + look * m[3], clear) for m in mates.tolist() if m[4] != me_id]
    if ball_clear > 0.0:
        obst.append((ball_x, ball_y, ball_clear))
    seen = {}  # index -> (a, b, d) of the obstacles near the way
    first, first_a = -1, 1e18
    for k, (x, y, c) in enumerate(obst):
        rx, ry = x - px, y - py
        d = math.sqrt(rx * rx + ry * ry)
        if d > length + c or math.sqrt((x - tx) * (x - tx) + (y - ty) * (y - ty)) < c:
            continue
        a, b = rx * ux + ry * uy, ry * ux - rx * uy
        seen[k] = (a, b, d)
        if ((0.0 < a < length and abs(b) < c) or (d < c and a > 0.0)) and a < first_a:
            first, first_a = k, a
    if first < 0:
        return tx, ty, 0
    group = {first}
    while True:
        more = [
            k
            for k in sorted(seen)
            if k not in group
            and any(
                (obst[k][0] - obst[g][0]) * (obst[k][0] - obst[g][0])
                + (obst[k][1] - obst[g][1]) * (obst[k][1] - obst[g][1])
                < GROUP_GAP * GROUP_GAP
                for g in group
            )
        ]
        if not more:
            break
        group.update(more)  # (a pass of the kernel may take several at once: the same group in the end)
    bounds, reach, nearest, nearest_d = [], 0.0, first, 1e18
    for k in sorted(group):
        a, b, d = seen[k]
        c = obst[k][2]
        phi = math.atan2(b, a)
        delta = 0.5 * math.pi if d <= c else math.asin(c / d)
        bounds.append((phi - delta, phi + delta))
        if a > 0.0 and d > reach:
            reach = d
        if d < nearest_d:
            nearest, nearest_d = k, d
    best, best_cost = None, 1e18
    for lo, hi in bounds:
        for angle in (_wrap(lo - 1e-3), _wrap(hi + 1e-3)):
            if abs(angle) > MAX_TURN or any(
                lo2 < angle < hi2 or lo2 < angle - TWO_PI < hi2 or lo2 < angle + TWO_PI < hi2 for lo2, hi2 in bounds
            ):
                continue
            cost = abs(angle) - (SIDE_HYSTERESIS if prefer_side != 0 and (angle > 0.0) == (prefer_side > 0) else 0.0)
            if cost < best_cost:
                best, best_cost = angle, cost
    if best is None:
        best = -MAX_TURN if seen[nearest][1] > 0.0 else MAX_TURN
    reach = max(min(reach if reach > 0.0 else length, length), 0.5)
    c, s = math.cos(best), math.sin(best)
    return px + reach * (c * ux - s * uy), py + reach * (s * ux + c * uy), 1 if best > 0.0 else -1


def test_sub_target_with_its_scratch_in_one_array_equals_the_one_before():
    """sub_target keeps its per-obstacle numbers in the rows of one array (one allocation instead of ten): the
    same points and sides as its rule in plain Python, bit for bit, on random crowds (clusters, the ball, the
    robot itself)."""
    import struct

    from simatch.strategy.nubot.avoidance import sub_target

    rng = random.Random(23)
    for _ in range(20_000):
        px, py = rng.uniform(-11, 11), rng.uniform(-7, 7)
        tx, ty = px + rng.uniform(-6, 6), py + rng.uniform(-6, 6)

        def near(px=px, py=py, tx=tx, ty=ty):
            return px + (tx - px) * rng.random() + rng.uniform(-1, 1), py + (ty - py) * rng.random() + rng.uniform(
                -1, 1
            )

        opps = np.array([(*near(), rng.uniform(-2, 2), rng.uniform(-2, 2)) for _ in range(rng.randint(0, 6))]).reshape(
            -1, 4
        )
        mates = np.array(
            [(*near(), rng.uniform(-2, 2), rng.uniform(-2, 2), k + 1) for k in range(rng.randint(0, 5))]
        ).reshape(-1, 5)
        args = (
            px,
            py,
            tx,
            ty,
            opps,
            mates,
            rng.randint(1, 5),
            *near(),
            rng.choice([0.0, 0.45]),
            1.1,
            0.3,
            rng.choice([-1, 0, 1]),
        )
        got, want = sub_target(*args), _plain_sub_target(*args)
        assert struct.pack("2d", *got[:2]) == struct.pack("2d", *want[:2]) and got[2] == want[2], args


def test_the_team_table_and_records_are_those_of_the_records_made_one_by_one():
    """`TeamView.get` writes its Mate records' slots and its table in one pass: the same fields as
    `Mate(info, ...)` gives and the table np.array makes of them, for every robot of a running match."""
    from simatch.strategy.nubot.observation import Mate, TeamView

    with simatch.Simulation("msl_5v5", seed=1) as sim:
        for _ in range(6):
            sim.run(seconds=1.5, until_done=False)
            for node in sim.robot_nodes.values():
                world = node.world
                mates, by_id, table = TeamView().get(world)
                expect = []
                for k, r in enumerate(world.vision.robots):
                    s = world.strategies.get(r.id)
                    if s is None:
                        m = Mate(r, r.id == world.goalkeeper)
                    else:
                        user = s.user.tolist()
                        att, rt = (int(user[0]), user[1]) if len(user) >= 2 else (-1, 1e9)
                        pi = s.pass_cmd if s.pass_cmd.is_valid else None
                        m = Mate(r, r.id == world.goalkeeper, s.role, s.action, pi, att, rt)
                    m.row = k
                    expect.append(m)
                    assert by_id[r.id] is mates[k]
                for got, want in zip(mates, expect, strict=True):
                    assert [getattr(got, f) for f in Mate.__slots__] == [getattr(want, f) for f in Mate.__slots__]
                rows = [(m.x, m.y, m.vx, m.vy, m.id, m.yaw, m.role, m.role_time) for m in expect]
                assert table.tobytes() == np.array(rows, dtype=np.float64).reshape(-1, 8).tobytes()


def test_a_team_mates_observation_is_the_one_made_afresh():
    """`observe` with the team's shared view (its records, table and opponents, and the ball's nearest team-mate
    and opponent a team-mate found at the same tick) gives, slot for slot, the Observation a robot makes from a
    fresh view, for every robot of a running match; `Observation(world, view)` is the same record."""
    from simatch.strategy.nubot.observation import Mate, Observation, TeamView, observe

    def slots(obs):
        out = []
        for name in Observation.__slots__:
            value = getattr(obs, name)
            if isinstance(value, Mate):
                value = [getattr(value, f) for f in Mate.__slots__]
            elif isinstance(value, list) and value and isinstance(value[0], Mate):
                value = [[getattr(m, f) for f in Mate.__slots__] for m in value]
            elif isinstance(value, dict):
                value = {k: [getattr(m, f) for f in Mate.__slots__] for k, m in value.items()}
            elif isinstance(value, np.ndarray):
                value = (value.shape, value.tobytes())
            elif isinstance(value, float):
                value = struct.pack("d", value)
            out.append((name, value))
        return out

    cached = 0
    with simatch.Simulation("msl_5v5", seed=1) as sim:
        for _ in range(8):
            sim.run(seconds=1.3, until_done=False)
            for node in sim.robot_nodes.values():
                world, view = node.world, node.strategy.shared.view
                cached += view.opp_tick == world.tick and view.opp_bx == world.vision.ball.x
                got = observe(world, view)
                assert slots(got) == slots(Observation(world, TeamView()))
                assert slots(Observation(world, view)) == slots(got)
    assert cached > 20


def test_a_kept_formation_is_the_one_its_key_says():
    """The team picture keeps the last set-piece formation with `_formation_key` of its inputs: for the set
    pieces it keeps, any opponents and assistant's place of the same key give the same slots, bit for bit
    (the signs of zeros too); the other set pieces have no key."""
    from simatch.strategy.nubot.params import NubotParams, plain
    from simatch.strategy.nubot.setpieces import formation

    params = plain(NubotParams())
    areas = Areas(FieldGeometry(), params.robot_radius + 0.15)
    spots = positions.spot_grid(areas)
    rng = random.Random(16)

    def crowd():
        return [(rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0) for _ in range(rng.randint(0, 5))]

    def exact(slots):
        return [tuple(v.hex() if isinstance(v, float) else v for v in s) for s in slots]

    for kind in range(1, 16):
        if kind not in (1, 2, 5, 6, 13):
            assert picture._formation_key(kind, 1.0, 2.0, crowd()) is None
    for _ in range(3000):
        kind = rng.choice([1, 2, 5, 6, 13])
        bx = rng.choice([0.0, -0.0, rng.uniform(-11, 11)])
        by = rng.choice([0.0, -0.0, rng.uniform(-7, 7)])
        a, b = crowd(), crowd()
        key = picture._formation_key(kind, bx, by, a)
        if picture._formation_key(kind, bx, by, b) != key:
            continue
        near = [None, (rng.uniform(-11, 11), rng.uniform(-7, 7))]
        want = exact(formation(kind, areas, bx, by, a, params, spots, near[0]))
        assert exact(formation(kind, areas, bx, by, b, params, spots, near[1])) == want
        if by == 0.0:  # a zero of the other sign is another key
            assert picture._formation_key(kind, bx, -by, a) != key


def test_the_ball_path_with_inline_min_and_max_is_the_one_before():
    """`BallPath`'s stop point and `at` take Python's min and max inline: the same numbers, bit for bit, as
    the calls they replace, on random paths (flying, rolling, at rest, against the boards) and times."""

    def hexes(*vs):
        return tuple(v.hex() for v in vs)

    rng = random.Random(8)
    for _ in range(20_000):
        path = _random_path(rng)
        if path.speed >= 0.05:
            roll_t = path.speed / path.decel
            s_stop = path.speed * path.land_t + path.speed * roll_t - 0.5 * path.decel * roll_t * roll_t
            want = (
                min(max(path.x + path.ux * s_stop, -path.xlim), path.xlim),
                min(max(path.y + path.uy * s_stop, -path.ylim), path.ylim),
            )
            assert hexes(path.stop_x, path.stop_y) == hexes(*want)
        t = rng.choice([0.0, 0.4, path.land_t, path.stop_t, rng.uniform(0.0, 5.0)])
        if path.speed < 0.05 or t <= 0.0:
            want = (path.x, path.y)
        elif t >= path.stop_t:
            want = (path.stop_x, path.stop_y)
        else:
            tr = max(0.0, t - path.land_t)
            s = path.speed * (min(t, path.land_t) + tr) - 0.5 * path.decel * tr * tr
            want = (
                min(max(path.x + path.ux * s, -path.xlim), path.xlim),
                min(max(path.y + path.uy * s, -path.ylim), path.ylim),
            )
        assert hexes(*path.at(t)) == hexes(*want)


def _score_spots_before(cx, cy, bx, by, ox, oy, L2, dmin, dmax, nx, ny, out):
    """`positions._score_spots` as it was before it took square roots only where they count."""
    for i in range(cx.shape[0]):
        x, y = cx[i], cy[i]
        score = -0.45 * math.sqrt((L2 - x) ** 2 + y * y)
        if abs(y) < 3.0:
            score += 0.4 * min(x, 2.0)
        dball = math.sqrt((x - bx) ** 2 + (y - by) ** 2)
        score -= 3.0 * max(0.0, dmin - dball) + 1.0 * max(0.0, dball - dmax)
        sx, sy = x - bx, y - by
        ll = sx * sx + sy * sy + 1e-9
        lane = 1e9
        for k in range(ox.shape[0]):
            dopp = math.sqrt((x - ox[k]) ** 2 + (y - oy[k]) ** 2)
            score -= 2.0 * max(0.0, 2.5 - dopp)
            t = min(max(((ox[k] - bx) * sx + (oy[k] - by) * sy) / ll, 0.0), 1.0)
            lane = min(lane, math.sqrt((bx + t * sx - ox[k]) ** 2 + (by + t * sy - oy[k]) ** 2))
        if ox.shape[0] > 0:
            if lane < 0.85:
                score -= 4.0
            score -= 1.5 * max(0.0, 1.4 - lane)
        if nx == nx:
            score -= 0.12 * math.sqrt((x - nx) ** 2 + (y - ny) ** 2)
        out[i] = score


def test_spot_scores_with_fewer_square_roots_equal_the_ones_before():
    """`_score_spots` takes an opponent's distance only within 2.5 m and one square root of the nearest
    lane: the same scores, bit for bit, as before (compiled both), on random spots, balls and opponents
    (opponents exactly 2.5 m from a spot, on a spot, on the ball, NaN, none)."""
    import numba

    before = numba.njit(_score_spots_before)
    areas = Areas(FieldGeometry(), 0.55)
    cx, cy = positions.spot_grid(areas)
    rng = random.Random(25)
    for _ in range(3000):
        bx, by = rng.uniform(-11, 11), rng.uniform(-7, 7)
        opps = []
        for _ in range(rng.randint(0, 6)):
            kind = rng.random()
            if kind < 0.15:  # exactly 2.5 m from a spot (or as near as floats get)
                k = rng.randrange(len(cx))
                a = rng.choice([0.0, 0.5 * math.pi, rng.uniform(0, 2 * math.pi)])
                opps.append((cx[k] + 2.5 * math.cos(a), cy[k] + 2.5 * math.sin(a)))
            elif kind < 0.25:
                k = rng.randrange(len(cx))
                opps.append((cx[k], cy[k]))
            elif kind < 0.3:
                opps.append((bx, by))
            elif kind < 0.33:
                opps.append((math.nan, rng.uniform(-7, 7)))
            else:
                opps.append((rng.uniform(-11, 11), rng.uniform(-7, 7)))
        ox = np.array([o[0] for o in opps], dtype=float)
        oy = np.array([o[1] for o in opps], dtype=float)
        nx, ny = (rng.uniform(-11, 11), rng.uniform(-7, 7)) if rng.random() < 0.7 else (math.nan, math.nan)
        dmin, dmax = rng.choice([(3.0, 8.5), (2.5, 6.5)])
        want, got = np.empty(len(cx)), np.empty(len(cx))
        before(cx, cy, bx, by, ox, oy, areas.L2, dmin, dmax, nx, ny, want)
        positions._score_spots(cx, cy, bx, by, ox, oy, areas.L2, dmin, dmax, nx, ny, got)
        assert want.tobytes() == got.tobytes()


def _intercepts_before(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, px, py, vx, vy, extra, vmax, acc, out):
    """`ballpath._intercepts` as it was before it sampled the path once and passed over samples out of reach."""
    for r in range(px.shape[0]):
        for k in range(ballpath.SAMPLES):
            t = k * ballpath.STEP
            if speed < 0.05:
                bx, by = x, y
            else:
                tt = min(t, stop_t)
                tr = max(0.0, tt - land_t)
                s = speed * (min(tt, land_t) + tr) - 0.5 * decel * tr * tr
                bx = min(max(x + ux * s, -xlim), xlim)
                by = min(max(y + uy * s, -ylim), ylim)
            dx, dy = bx - px[r], by - py[r]
            d = math.sqrt(dx * dx + dy * dy) + 1e-9
            vpar = (vx[r] * dx + vy[r] * dy) / d
            vperp = math.sqrt(max(0.0, vx[r] * vx[r] + vy[r] * vy[r] - vpar * vpar))
            v0 = min(max(vpar, -vmax), vmax)
            t_stop = 0.0
            if v0 < 0.0:
                t_stop = -v0 / acc
                d += v0 * v0 / (2.0 * acc)
                v0 = 0.0
            d_acc = (vmax * vmax - v0 * v0) / (2.0 * acc)
            if d <= d_acc:
                reach = (math.sqrt(v0 * v0 + 2.0 * acc * d) - v0) / acc
            else:
                reach = (vmax - v0) / acc + (d - d_acc) / vmax
            reach += t_stop + 0.5 * vperp / acc + ballpath.CATCH_MARGIN + extra[r]
            if reach <= t or k == ballpath.SAMPLES - 1:
                out[r, 0] = max(t, reach)
                out[r, 1] = bx
                out[r, 2] = by
                break


def test_intercepts_sampled_once_and_passing_over_samples_out_of_reach_equal_the_ones_before():
    """`_intercepts` samples the ball's path once for all robots and passes over the samples a robot cannot
    reach in time at top speed: the same interceptions, bit for bit, as before (compiled both), on random
    paths and robots (near the ball, fast, extra delays below zero, a robot that reaches a sample just in
    time, none that can, a NaN, odd speed limits)."""
    import numba

    before = numba.njit(_intercepts_before)
    rng = random.Random(40)
    for _ in range(6000):
        path = _random_path(rng)
        n = rng.randint(1, 10)
        px = np.array([rng.choice([path.x + rng.uniform(-0.5, 0.5), rng.uniform(-12, 12)]) for _ in range(n)])
        py = np.array([rng.choice([path.y + rng.uniform(-0.5, 0.5), rng.uniform(-8, 8)]) for _ in range(n)])
        vx = np.array([rng.choice([0.0, rng.uniform(-4, 4)]) for _ in range(n)])
        vy = np.array([rng.choice([0.0, rng.uniform(-4, 4)]) for _ in range(n)])
        extra = np.array([rng.choice([0.0, rng.uniform(0.0, 2.0), rng.uniform(-1.0, 0.0)]) for _ in range(n)])
        if rng.random() < 0.05:
            px[0] = math.nan
        vmax = rng.choice([rng.uniform(1.0, 4.0), rng.uniform(1.0, 4.0), 0.0, 1e-3, 50.0])
        acc = rng.choice([rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0), 0.0, 1e-3, 50.0])
        want, got = np.full((n, 3), 7.0), np.full((n, 3), 7.0)
        outcomes = []
        for kernel, out in ((before, want), (ballpath._intercepts, got)):
            try:
                kernel(*path.kernel_args(), px, py, vx, vy, extra, vmax, acc, out)
                outcomes.append(None)
            except ZeroDivisionError:  # (no speed or no acceleration: numba raises as Python would)
                outcomes.append(ZeroDivisionError)
        assert outcomes[0] is outcomes[1]
        assert want.tobytes() == got.tobytes()


def test_time_to_cover_and_pass_speed_with_inline_min_and_max_are_the_ones_before():
    """`time_to_cover` and `pass_speed` take Python's min and max of two inline: the same numbers, bit for
    bit (NaN and the limits themselves included)."""
    from simatch.strategy.nubot.evaluate import pass_speed
    from simatch.strategy.nubot.geometry import time_to_cover

    def ttc_before(d, v0, vmax, acc):
        v0 = min(max(v0, 0.0), vmax)
        d_acc = (vmax * vmax - v0 * v0) / (2.0 * acc)
        if d <= d_acc:
            return (math.sqrt(v0 * v0 + 2.0 * acc * d) - v0) / acc
        return (vmax - v0) / acc + (d - d_acc) / vmax

    def same(a, b):
        return (math.isnan(a) and math.isnan(b)) or a.hex() == b.hex()

    rng = random.Random(31)
    for _ in range(20_000):
        vmax = rng.choice([3.0, rng.uniform(0.5, 4.0)])
        v0 = rng.choice([0.0, -0.0, vmax, math.nan, rng.uniform(-5.0, 5.0)])
        d, acc = rng.choice([0.0, rng.uniform(0.0, 20.0)]), rng.uniform(0.5, 3.0)
        assert same(time_to_cover(d, v0, vmax, acc), ttc_before(d, v0, vmax, acc))
        lo, hi = rng.choice([(1.6, 7.5), (1.8, 4.0)])
        dist = rng.choice([0.0, rng.uniform(0.0, 30.0), math.nan])
        arrival, decel = rng.choice([lo, rng.uniform(0.0, 3.0)]), rng.uniform(0.2, 0.8)
        want = min(hi, max(lo, math.sqrt(arrival * arrival + 2.0 * decel * dist)))
        assert same(pass_speed(dist, arrival, decel, lo, hi), want)
