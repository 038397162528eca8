"""What nubot's compiled parts promise: the routes round the areas, the assistants' spots, the interceptions
in one kernel, the opponents' array shared within a team only when it is the same, a robot alone deciding
as in its team, and the kernels the benchmark loads before timing."""

import math
import random
import struct

import numpy as np

import simatch
from simatch.field import FieldGeometry
from simatch.strategy.nubot import assignment, ballpath, observation, picture, positions
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
        "assist_spots": assignment.assist_spots,
        "assign": assignment._assign_flat,
        "open_slots": assignment.open_slots,
        "passive_point": positions.passive_point,
        "midfield_point": positions.midfield_point,
        "outlet_point": positions.outlet_point,
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


def test_the_intercepts_sample_the_path_where_ball_at_puts_the_ball():
    """Every interception point is a sample of the ball's path as `BallPath.at` (`ball_at`) gives it, bit
    for bit: at its sample time when the robot gets there in time, else at the last sample (4 s)."""
    rng = random.Random(7)
    times = [k * ballpath.STEP for k in range(ballpath.SAMPLES)]
    for _ in range(500):
        path = _random_path(rng)
        n = rng.randint(1, 6)
        px, py = np.array([rng.uniform(-12, 12) for _ in range(n)]), np.array([rng.uniform(-8, 8) for _ in range(n)])
        v = np.array([rng.uniform(-3, 3) for _ in range(n)])
        out = ballpath.intercepts(path, px, py, v, v[::-1].copy(), rng.uniform(1.0, 4.0), rng.uniform(1.0, 3.0))
        for t, x, y in out:
            at = times[-1] if t not in times else t
            assert (x, y) == path.at(at), (t, at)


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


def test_a_move_is_the_command_of_its_fields():
    """`Command.move` makes the Command the dataclass makes of the same fields (every other one at its
    default), and `Motion.move` is the last `go` as such a command, its target as the intent."""
    from simatch.strategy.base import Command
    from simatch.strategy.nubot.observation import Observation, TeamView

    move = Command.move(1.5, -0.25, 0.3, 3, 2, (4.0, 1.0), (1.0, 0.5))
    assert type(move) is Command
    assert move == Command(vx=1.5, vy=-0.25, w=0.3, role=3, action=2, intent=(4.0, 1.0), user=(1.0, 0.5))
    with simatch.Simulation("msl_5v5", seed=1) as sim:
        sim.run(seconds=1.0, until_done=False)
        node = sim.robot_nodes["cyan/3"]
        robot = node.strategy
        obs = Observation(node.world, TeamView())
        vx, vy, w = robot.motion.go(obs, 2.0, -1.0, 0.5, 2.0, 3.0)
        assert robot.motion.move(3, 4) == Command(vx=vx, vy=vy, w=w, role=3, action=4, intent=(2.0, -1.0))


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
                (
                    r.x,
                    r.y,
                    r.role,
                    hysteresis + (assignment.NEW_ROLE_HOLD if r.role_time < assignment.MIN_ROLE_TIME else 0.0),
                )
                for r in robots
            ],
            4,
        )
        cx, cy, cr = around if around is not None else (0.0, 0.0, -1.0)
        best = assignment._assign(rows, _array([(s[1], s[2], s[0]) for s in kept], 3), cx, cy, cr)
        want = {robots[i].id: int(best[i]) for i in range(min(n, len(kept)))}
        assert assignment.assign(robots, slots, hysteresis, around) == want


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


def test_the_team_table_and_records_are_those_of_the_records_made_one_by_one():
    """`TeamView.get` writes its Mate records' slots and its table in one pass: each record holds its robot's
    RobotInfo and StrategyInfo fields, and the table np.array makes of them, for every robot of a running
    match."""
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
                    role, action, pi, att, rt = -1, -1, None, -1, 1e9
                    if s is not None:
                        user = s.user.tolist()
                        att, rt = (int(user[0]), user[1]) if len(user) >= 2 else (-1, 1e9)
                        pi = s.pass_cmd if s.pass_cmd.is_valid else None
                        role, action = s.role, s.action
                    info = (r.id, r.x, r.y, r.yaw, r.vx, r.vy, r.w, r.holding_ball, r.valid, r.stuck)
                    m = Mate(*info, role, action, pi, r.id == world.goalkeeper, att, rt, k)
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


def test_assistant_spots_are_the_best_scored_at_least_3_m_apart():
    """`assist_spots` takes, among the twelve best scored candidates (the first of equal scores first), each
    one at least 3 m from those taken before it, best first, up to the number asked for."""
    areas = Areas(FieldGeometry(), 0.4)
    cx, cy = positions.spot_grid(areas)
    rng = random.Random(11)
    for case in range(500):
        opps = np.array([[rng.uniform(-11, 11), rng.uniform(-7, 7), 0.0, 0.0] for _ in range(rng.randint(0, 5))])
        opps = opps.reshape(-1, 4)
        bx, by = (0.0, 0.0) if case % 10 == 0 else (rng.uniform(-11, 11), rng.uniform(-7, 7))
        nx, ny = (math.nan, math.nan) if rng.random() < 0.3 else (rng.uniform(-11, 11), rng.uniform(-7, 7))
        n = rng.choice([1, 2, 12])
        score = np.empty(len(cx))
        positions._score_spots(cx, cy, bx, by, opps[:, 0].copy(), opps[:, 1].copy(), areas.L2, 3.0, 8.5, nx, ny, score)
        best = sorted(range(len(cx)), key=lambda k: (-score[k], k))[:12]
        want = []
        for k in best:
            if all(math.hypot(cx[k] - x, cy[k] - y) > 3.0 for x, y in want) and len(want) < n:
                want.append((cx[k], cy[k]))
        out = np.empty((n, 2))
        got = assignment.assist_spots(cx, cy, bx, by, opps, areas.L2, 3.0, 8.5, nx, ny, out)
        assert out[:got].tolist() == [list(w) for w in want]


def test_open_play_slots_are_the_roles_points_inside_the_field_and_apart():
    """`open_slots` gives each robot of the rest one of the roles of its size (two assistants from four
    robots on), at the roles' points kept inside the field and at least SLOT_GAP apart (unless three slides
    could not part them), no two robots the same slot."""
    areas = Areas(FieldGeometry(), 0.4)
    rng = random.Random(21)
    for _ in range(500):
        k = rng.randint(1, 6)
        table = np.array(
            [
                (rng.uniform(-12, 12), rng.uniform(-8, 8), 0.0, 0.0, j + 1, 0.0, rng.choice([-1, 2, 3, 4]), 1e9)
                for j in range(k)
            ]
        )
        rest = np.array(sorted(rng.sample(range(k), rng.randint(1, k))), dtype=np.int64)
        attacking = rng.random() < 0.5
        bx, by = rng.uniform(-10, 10), rng.uniform(-6, 6)
        assist = np.array([(rng.uniform(-10, 10), rng.uniform(-6, 6)) for _ in range(2)])
        out = np.empty((len(rest), 4))
        got = assignment.open_slots(
            table, rest, attacking, assist, -6.0, 1.0, -3.0, -2.0, bx, by, areas.pitch, 0.5, out
        )
        assert got == min(len(rest), 4)
        slots = out[:got].tolist()
        assert len({int(s[0]) for s in slots}) == got
        roles = sorted(int(s[1]) for s in slots)
        n = len(rest)
        if n >= 4:
            want = [assignment.ASSISTANT, assignment.ASSISTANT, assignment.PASSIVE, assignment.MIDFIELD]
        else:
            order = [assignment.ASSISTANT, assignment.PASSIVE, assignment.MIDFIELD]
            if not attacking:
                order = [assignment.PASSIVE, assignment.MIDFIELD, assignment.ASSISTANT]
            want = order[:n]
        assert roles == sorted(want)
        for _, _, x, y in slots:
            assert abs(x) <= areas.L2 - assignment.SLOT_INSIDE + 1.3 and abs(y) <= areas.W2
