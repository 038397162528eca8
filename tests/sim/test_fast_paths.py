"""The simulator's per-step fast paths give exactly what the general ones give: the ModelStates message's
float32 arrays (one compiled call instead of the float64 states rounded) and the robots touching the ball
(the contact list left unread while no robot geom's bounding sphere reaches the ball's)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

import simatch
from simatch import msgs
from simatch.config.loader import shipped_scenes
from simatch.sim.kernels import ball_apart, mix64
from simatch.sim.simulator import FINGERPRINTS, fingerprint


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


@pytest.mark.parametrize("name", sorted(shipped_scenes()))
def test_state_fingerprint_is_the_fingerprint_of_the_exact_states(name):
    # the fingerprint a recording takes every control tick, from the block the simulator fills in place, equals
    # the one of the arrays `model_state_arrays` makes (what `replay --verify` recomputes), through a run
    with simatch.Simulation(name, seed=4) as run:
        sim = run.simulator
        seen = set()
        for _ in range(6):
            _, pose, twist = sim.model_state_arrays()
            fp = sim.state_fingerprint()
            assert fp == fingerprint(pose, twist)
            seen.add(fp)
            run.run(seconds=0.35, until_done=False)
        assert len(seen) > 1  # the states moved, and the fingerprint with them


def _mix64_by_hand(words: list[int]) -> int:
    """The fingerprint's definition (a round like xxHash64's per word, its final mix) in plain integers."""
    p1, p2, p3, mask = 0x9E3779B185EBCA87, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9, (1 << 64) - 1
    h = (len(words) * p3) & mask
    for w in words:
        h ^= (w * p2) & mask
        h = ((((h << 31) | (h >> 33)) & mask) * p1) & mask
    h ^= h >> 33
    h = (h * p2) & mask
    h ^= h >> 29
    h = (h * p3) & mask
    return h ^ (h >> 32)


def test_the_fingerprint_is_its_definition_on_every_input():
    # the compiled kernel against the definition in plain integers: lengths 0 to 200, random words and the corners
    rng = np.random.default_rng(7)
    for n in list(range(20)) + [143, 200] * 20:
        words = rng.integers(0, 2**64, size=n, dtype=np.uint64, endpoint=False)
        assert int(mix64(words)) == _mix64_by_hand(words.tolist())
    for corner in ([0], [2**64 - 1], [0] * 143, [2**64 - 1] * 143, [1 << k for k in range(64)]):
        assert int(mix64(np.array(corner, dtype=np.uint64))) == _mix64_by_hand(corner)


def test_the_fingerprint_tells_every_single_bit_apart():
    # a difference anywhere in the states, however small (each bit of each number flipped), changes it
    rng = np.random.default_rng(3)
    pose, twist = rng.normal(size=(11, 7)), rng.normal(size=(11, 6))
    base = fingerprint(pose, twist)
    seen = {base}
    for arr in (pose, twist):
        words = arr.view(np.uint64).reshape(-1)
        for i in range(0, words.size, 5):
            for bit in range(64):
                words[i] ^= np.uint64(1 << bit)
                seen.add(fingerprint(pose, twist))
                words[i] ^= np.uint64(1 << bit)
    assert fingerprint(pose, twist) == base and len(seen) == 1 + 64 * (len(range(0, 77, 5)) + len(range(0, 66, 5)))


@pytest.mark.parametrize("name", ["msl_5v5", "aerial_encirclement"])
def test_a_simulator_takes_the_fingerprint_of_an_older_recording_when_told(name):
    # `replay --verify` of a recording made before format 2 re-simulates with its SHA-256 fingerprints
    with simatch.Simulation(name, seed=4) as run:
        sim = run.simulator
        run.run(seconds=0.3, until_done=False)
        _, pose, twist = sim.model_state_arrays()
        assert sim.state_fingerprint() == fingerprint(pose, twist)
        sim.fingerprint_kind = "sha256"
        digest = hashlib.sha256(pose.tobytes() + twist.tobytes()).digest()
        assert sim.state_fingerprint() == fingerprint(pose, twist, "sha256") == int.from_bytes(digest[:8], "little")
        assert set(FINGERPRINTS) == {"mix64", "sha256"}
        with pytest.raises(ValueError, match="unknown fingerprint"):
            fingerprint(pose, twist, "md5")


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
                if ball_apart(sim.engine.geom_xpos, sim._touch_geoms, sim._touch_bound2, sim.ix.ball_geom):
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


# --- perception: one compiled call for exact perception of ground robots ------------------------------------


def _both_ways(sim, stamp=1.5, tick=7):
    """Every robot's OmniVisionInfo by `Simulator.observations` and by the general way (a snapshot observed by
    `Perception.observe`), from the same state: the 'stuck' timers and the noise generator are put back between
    the two. Returns (fast, general) as CDR bytes, and the 'stuck' flags of each."""
    p = sim.perception
    slow, rng = sim._slow_since.copy(), p.rng.bit_generator.state
    fast = [msgs.encode(m) for m in sim.observations(stamp, tick)]
    stuck_fast = np.array(sim.stuck)
    sim._slow_since[:] = slow
    p.rng.bit_generator.state = rng
    general = [msgs.encode(m) for m in p.observe(p.delayed(sim.snapshot()), stamp, tick)]
    return fast, general, stuck_fast, np.array(sim.stuck)


@pytest.mark.parametrize("name", sorted(shipped_scenes()))
def test_perception_of_every_shipped_world_equals_the_general_way(name):
    with simatch.Simulation(name, seed=3) as run:
        sim = run.simulator
        p = sim.perception
        # the compiled path is taken exactly where it applies: exact perception of ground robots alone
        exact = p.exact and p.sight is None and p.delay_steps == 0
        assert sim._sense_fast == (sim.aerial is None and exact and sim.n > 0)
        for _ in range(4):
            fast, general, stuck_fast, stuck_general = _both_ways(sim)
            assert fast == general
            assert np.array_equal(stuck_fast, stuck_general)
            run.run(seconds=0.7, until_done=False)


def test_perception_fast_path_equals_the_general_way_on_random_worlds():
    """Random poses and velocities (signed zeros, robots on the ball and on each other, far off the field),
    turned team frames, a holder, disabled robots, commanded set points that make robots stuck."""
    rng = np.random.default_rng(11)
    with simatch.Simulation("msl_5v5", seed=0) as run:
        sim = run.simulator
        assert sim._sense_fast
        n = sim.n
        seen_stuck = seen_invalid = 0
        for case in range(300):
            q, v = sim.engine.pose, sim.engine.twist
            q[:, :2] = rng.uniform(-13, 13, (n, 2))
            q[:, 2] = rng.uniform(-20, 20, n)
            v[:] = rng.normal(0, 2, (n, 3)) * (rng.random((n, 3)) < 0.7)
            b = sim.engine.ball_q
            sim.engine.qpos[b : b + 3] = rng.uniform(-10, 10, 3)
            sim.engine.qvel[sim.engine.ball_v : sim.engine.ball_v + 3] = rng.normal(0, 3, 3)
            if case % 5 == 0:  # a robot on the ball, another on top of a third, signed zeros
                sim.engine.qpos[b : b + 2] = q[0, :2]
                q[1, :2] = q[2, :2]
                q[3] = -0.0
                v[4] = -0.0
            sim.engine.setpoint[:] = rng.normal(0, 1.5, (n, 3))
            sim.enabled[:] = rng.random(n) > 0.1
            sim.ball.holder = int(rng.integers(-1, n))
            for team in ("cyan", "magenta"):
                sim.set_team_sign(team, int(rng.choice((-1, 1))))
            sim.step_index += int(rng.integers(1, 60))
            fast, general, stuck_fast, stuck_general = _both_ways(sim, float(rng.uniform(0, 100)), case)
            assert fast == general, case
            assert np.array_equal(stuck_fast, stuck_general)
            seen_stuck += int(stuck_fast.any())
            seen_invalid += sum(not m.robots[0].valid for m in sim.observations(0.0, 0))
        assert seen_stuck > 10 and seen_invalid > 10  # both flags exercised


def test_perception_fast_path_with_robots_of_fewer_wheels_equals_the_general_way(field_sim):
    """Three-wheel robots among four-wheel ones: each robot's wheel speeds are its own wheels' alone."""
    run = field_sim(**{"teams.magenta.model": "omni3"})
    sim = run.simulator
    assert sim._sense_fast and sim.perception._short_wheels
    run.run(seconds=0.3, until_done=False)
    for _ in range(3):
        sim.engine.twist[:] = np.random.default_rng(sim.step_index).normal(0, 1.5, (sim.n, 3))
        fast, general, stuck_fast, stuck_general = _both_ways(sim)
        assert fast == general
        run.run(seconds=0.2, until_done=False)
    sizes = {len(r.wheel_speeds) for m in sim.observations(0.0, 0) for r in m.robots}
    assert sizes == {3, 4}


def test_perception_messages_of_a_tick_are_new_arrays_and_shared_ones_are_read_only():
    """A subscriber may keep a message: the next tick's never writes into it. The obstacles' radii and heights,
    the same at every tick, are shared and read-only (as a decoded message's arrays are)."""
    with simatch.Simulation("msl_5v5", seed=2) as run:
        sim = run.simulator
        first = sim.observations(0.0, 0)
        kept = [(m.obstacles.x.copy(), m.robots[0].wheel_speeds.copy()) for m in first]
        run.run(seconds=0.5, until_done=False)
        second = sim.observations(0.5, 20)
        for m, (x, wheels) in zip(first, kept):
            assert np.array_equal(m.obstacles.x, x) and np.array_equal(m.robots[0].wheel_speeds, wheels)
        assert not np.shares_memory(first[0].obstacles.x, second[0].obstacles.x)
        assert first[0].obstacles.radius is second[0].obstacles.radius
        with pytest.raises(ValueError):
            first[0].obstacles.radius[0] = 1.0
        with pytest.raises(ValueError):
            first[0].obstacles.z[0] = 1.0


def test_velocity_commands_are_stored_as_the_rounded_numbers_the_general_way_stores():
    """`command_velocity` rounds through one struct and writes through memoryviews: the drive's numbers, the
    command's step and the dirty flag are what `msgs.f32s` and NumPy's item assignment give, for any kind of
    number it accepts (floats, NumPy scalars, ints, bools) and a NumPy integer as the index."""
    rng = np.random.default_rng(3)
    with simatch.Simulation("msl_5v5", seed=1) as run:
        sim = run.simulator
        run.run(seconds=0.1, until_done=False)
        kinds = [float, np.float64, np.float32, lambda v: int(round(v)), lambda v: v > 0]
        for k in range(500):
            i = int(rng.integers(sim.ng))
            values = [kinds[k % 5](v) for v in rng.normal(0.0, 3.0, 3)]
            index = np.int64(i) if k % 7 == 0 else i
            sim.drive.dirty[i] = False
            assert sim.command_velocity(index, *values) is True
            assert sim.drive.cmd[i].tolist() == list(msgs.f32s(*(float(v) for v in values)))
            assert sim.drive.dirty[i] and sim.drive.any_dirty and sim.last_command_step[i] == sim.step_index
            sim.step()
        with pytest.raises(IndexError):
            sim.command_velocity(sim.n, 0.0, 0.0, 0.0)
        assert sim.command_velocity(0, "1", 0.0, 0.0) is False and sim.command_velocity(0, np.nan, 0, 0) is False


# --- the per-step kernels called without numba's dispatcher ----------------------------------------------------


def test_bound_kernels_compute_what_the_dispatcher_computes():
    """`simatch.compiled.bind` gives the kernel compiled for its declared signature; called with arguments of
    those kinds it returns what numba's dispatcher returns."""
    from simatch.compiled import bind
    from simatch.sim.kernels import model_states32

    rng = np.random.default_rng(5)
    qpos, qvel = rng.normal(size=40), rng.normal(size=40)
    states32, apart = bind(model_states32), bind(ball_apart)
    for _ in range(20):
        qpos[:], qvel[:] = rng.normal(size=40), rng.normal(size=40)
        a = (np.zeros(28, np.float32), np.zeros(24, np.float32))
        b = (np.zeros(28, np.float32), np.zeros(24, np.float32))
        model_states32(qpos, qvel, 0, 0, 3, 9, 9, *a)
        states32(qpos, qvel, 0, 0, 3, 9, 9, *b)
        assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes()
        xpos, geoms, bound2 = rng.normal(size=(6, 3)), np.arange(1, 6, dtype=np.int64), rng.uniform(0, 3, 5)
        assert apart(xpos, geoms, bound2, 0) == ball_apart(xpos, geoms, bound2, 0)


def test_held_ball_kernels_bound_play_the_match_the_dispatcher_plays():
    """The held ball's kernels (keep, roll, catch, the mouth's) bound by `simatch.compiled.bind` at the start
    give the same steps as their dispatchers: a stretch with catches, holds and losses of the ball played both
    ways ends in the same state, bit for bit."""
    from simatch.sim import kernels

    def play(dispatch: bool) -> str:
        with simatch.Simulation("msl_5v5", seed=3) as run:
            ball = run.simulator.ball
            if dispatch:
                ball._keep_kernel, ball._roll, ball._catch_kernel, ball._in_mouth, ball._mouth_vel = (
                    kernels.keep_ball,
                    kernels.roll_held_ball,
                    kernels.catch_candidate,
                    kernels.in_mouth,
                    kernels.mouth_velocity,
                )
            run.run(seconds=12.0, until_done=False)
            assert run.simulator.mechanics["dribble_start"] > 0  # the ball was caught (and held) in the stretch
            return run.state_digest()

    assert play(True) == play(False)
