"""Reproduction from the recorded world inputs (``simatch replay FILE --verify``, the default): every input of
the world is recorded where it enters the simulator, and a fresh simulator given those inputs alone follows
the run bit for bit — whatever made them: strategies with unseeded randomness, a judge placing the ball at
random, a script, a scripted driver. A change that bypasses the simulator's inputs is caught where it is."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import mujoco
import numpy as np
import pytest

import simatch
from simatch import msgs
from simatch.bus import Node, Phase, topics
from simatch.record import Recorder, Recording, VerifyError, verify
from simatch.sim.inputs import CALL, VEL, InputError, WorldReplay
from simatch.sim.simulator import Simulator

from .conftest import NOISY, record_run

SIMATCH = [sys.executable, "-m", "simatch"]
WANDERER = "tests.record.random_plugins:Wanderer"
DICE = "tests.record.random_plugins:DiceJudge"


def test_a_recorded_run_reproduces_from_its_inputs(recording):
    path, _ = recording
    proc = subprocess.run(
        SIMATCH + ["replay", str(path), "--verify", "--json"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["identical"] and out["complete"] and out["compared"] == 400 and out["mode"] == "inputs"
    assert out["inputs"] > 1000 and out["first_difference"] is None
    text = subprocess.run(SIMATCH + ["replay", str(path), "--verify"], capture_output=True, text=True, timeout=300)
    assert "re-simulated from" in text.stdout and "recorded world input(s)" in text.stdout


def test_the_inputs_are_every_command_as_applied(recording):
    """Every VelCmd a robot published is an input of the step it was applied at, with its numbers."""
    path, _ = recording
    rec = Recording(path)
    assert rec.metadata["world_inputs"] == "1"
    vel = {}
    for topic, _, msg in rec.messages(topics={topics.WORLD_INPUTS, "cyan/3/VelCmd"}):
        if topic == "cyan/3/VelCmd":
            vel.setdefault(round(msg.stamp / 0.005), []).append((msg.vx, msg.vy, msg.w))
    applied = {}
    index = simatch.Simulation("msl_5v5", overrides=NOISY).simulator.index_of("cyan/3")
    for _, _, msg in rec.messages(topics={topics.WORLD_INPUTS}):
        at = 0
        for kind, robot in zip(msg.kind.tolist(), msg.robot.tolist()):
            width = 3 if kind == VEL else 4 if kind != CALL else 0
            if kind == VEL and robot == index:
                applied.setdefault(int(msg.step), []).append(tuple(msg.values[at : at + 3]))
            at += width
    assert vel and applied == vel


def test_unseeded_plugins_reproduce_only_from_their_inputs(tmp_path):
    """Strategies and a judge drawing from the operating system's entropy: two runs differ, and each one's
    recording re-simulates bit for bit from its inputs (and not from its strategies)."""
    overrides = {"judge.kind": DICE, "teams.cyan.strategy": WANDERER, "teams.magenta.strategy": WANDERER}
    digests = []
    for k in range(2):
        path = tmp_path / f"dice{k}.mcap"

        def script(sim):
            for coach in sim.coaches.values():
                coach.start_play()
            sim.run(seconds=2.0)

        digests.append(record_run(path, seed=1, overrides=overrides, script=script))
        verdict = verify(path)
        assert verdict.identical and verdict.mode == "inputs" and verdict.compared == 400, verdict.describe()
        calls = [m for _, _, m in Recording(path).messages(topics={topics.WORLD_INPUTS}) if CALL in m.kind.tolist()]
        assert calls[0].step == 0 and calls[0].before_sense  # the judge's placement before the first step
        assert not verify(path, mode="strategies").identical
    assert digests[0] != digests[1]


class _Scripted(Node):
    """A scripted driver: every robot's velocity (and dribbler) at once, random, at every physics step."""

    phase = Phase.ROBOT
    name = "test/scripted"

    def __init__(self, sim):
        self.sim, self.period = sim, sim.dt
        self.rng = np.random.default_rng()  # unseeded

    def tick(self, now: float) -> None:
        n = self.sim.simulator.n
        V = self.rng.uniform(-2.0, 2.0, (n, 3))
        if self.rng.random() < 0.05:
            V[self.rng.integers(n), 0] = np.nan  # refused, as it was in the run
        self.sim.simulator.command_all(V, self.rng.random(n) < 0.3)


def test_a_scripted_driver_reproduces(tmp_path):
    path = tmp_path / "scripted.mcap"
    overrides = {"judge.kind": "none", "teams.cyan.strategy": "none", "teams.magenta.strategy": "none"}
    with simatch.Simulation("msl_5v5", seed=3, overrides=overrides) as sim:
        with Recorder.for_run(sim, path):
            sim.clock.add(_Scripted(sim))
            sim.run(seconds=1.0)
            assert sim.simulator.refused.sum() > 0
    assert verify(path).identical


def _run_changed_below_the_inputs(path, change):
    """Record 1 s in which ``change(sim)`` moves magenta/2 at 0.5 s without any input of the simulator."""

    def sneaky(sim):
        for coach in sim.coaches.values():
            coach.start_play()
        sim.run(seconds=0.5)
        change(sim.simulator)
        sim.run(seconds=0.5)

    record_run(
        path,
        overrides={**NOISY, "teams.cyan.strategy": "startpose", "teams.magenta.strategy": "startpose"},
        script=sneaky,
    )
    verdict = verify(path)
    assert not verdict.identical and verdict.mode == "inputs"
    # moved between steps 99 and 100: the world as step 100 takes it differs first
    assert (verdict.component.step, verdict.component.component) == (100, "inputs"), verdict.describe()
    return verdict.first_difference


def _move(sim: Simulator, dx: float) -> None:
    sim.d.qpos[sim.ix.robot_qpos[sim.index_of("magenta/2"), 0]] += dx
    mujoco.mj_forward(sim.m, sim.d)


def test_a_change_below_the_inputs_is_caught(tmp_path):
    diff = _run_changed_below_the_inputs(tmp_path / "moved.mcap", lambda sim: _move(sim, 1.0))
    assert (diff.step, diff.model, diff.field) == (100, "magenta/2", "x")
    assert diff.recorded == pytest.approx(diff.simulated + 1.0, abs=1e-5)


def test_a_change_below_float32_is_caught_by_the_fingerprint(tmp_path):
    diff = _run_changed_below_the_inputs(tmp_path / "nudged.mcap", lambda sim: _move(sim, 1e-9))
    assert (diff.step, diff.model, diff.field) == (100, "(every model)", "fingerprint of the exact states")


def test_a_recording_without_inputs_is_verified_from_its_strategies(tmp_path):
    """A recording that holds no world inputs (a plain bus recorder, an older simatch): ``--verify`` falls back
    to the strategies and says so; ``--verify inputs`` refuses with one line."""
    path = tmp_path / "plain.mcap"
    with simatch.Simulation("omni_circle", seed=2) as sim:
        with Recorder(sim.bus, path, scene=sim.scene, seed=sim.seed, dt=sim.dt):
            sim.run(seconds=0.5)
    verdict = verify(path)
    assert verdict.identical and verdict.mode == "strategies"
    assert any("no world inputs" in p for p in verdict.problems)
    with pytest.raises(VerifyError, match="holds no world inputs"):
        verify(path, mode="inputs")
    proc = subprocess.run(
        SIMATCH + ["replay", str(path), "--verify", "inputs"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 2 and "holds no world inputs" in proc.stderr and "Traceback" not in proc.stderr


def test_malformed_inputs_are_refused_with_a_clear_error():
    sim = Simulator(simatch.Simulation("omni_circle").scene.spec)
    replay = WorldReplay(sim)

    def inputs(**fields):
        base = dict(stamp=0.0, step=0, kind=np.array([VEL], np.uint8), robot=np.array([0], np.int16))
        base["values"] = np.zeros(3)
        base.update(fields)
        return msgs.new(msgs.WorldInputs, **base)

    replay.apply(inputs())  # a good one
    with pytest.raises(InputError, match="do not match"):
        replay.apply(inputs(values=np.zeros(2)))
    with pytest.raises(InputError, match="names robot 7"):
        replay.apply(inputs(robot=np.array([7], np.int16)))
    call = dict(kind=np.array([CALL], np.uint8), robot=np.array([-1], np.int16), values=np.zeros(0))
    with pytest.raises(InputError, match="not an input of the simulator"):
        replay.apply(inputs(**call, calls=['["step", [], {}]']))
    with pytest.raises(InputError, match="does not read"):
        replay.apply(inputs(**call, calls=["{nope"]))
    with pytest.raises(InputError, match="given at step"):
        replay.apply(inputs(step=5))
    replay.apply(inputs(**call, calls=['["set_model_state", ["nobody"], {"x": 1.0}]']))  # refused, as in a run
    assert replay.refused == 1


CALLS = [  # (method, args, kwargs): the common forms and every odd one
    ("command_velocity", (0, 0.5, -0.25, 0.125), {}),
    ("command_velocity", (1, np.float32(0.1), 1, True), {}),  # numpy, int and bool numbers, as given
    ("command_velocity", (2, "fast", 0.0, 0.0), {}),  # refused by the simulator, logged as given
    ("command_velocity", (3, float("nan"), 0.0, 0.0), {}),
    ("command_velocity", (0, 0.1, 0.2, 0.3, 0.0), {}),  # five arguments: a call
    ("command_velocity", (0, 0.1, 0.2), {"w": 0.3}),  # a keyword: a call
    ("command_velocity", (np.int64(1), 0.1, 0.2, 0.3), {}),  # not a plain int index: a call
    ("command_velocity", (True, 0.1, 0.2, 0.3), {}),
    ("command_action", (0, True), {}),
    ("command_action", (1, 0, 3.5), {}),
    ("command_action", (2, 1, 2.0, True), {}),
    ("command_action", (3, True, 1.0, False, 0.3), {}),
    ("command_action", (3, True, 1.0, False, None), {}),
    ("command_action", (4, [], np.float64(2.0), 1), {}),
    ("command_action", (0, True), {"kick_speed": 1.0}),
    ("command_action", (0, True, "hard"), {}),  # refused, logged as given
]


def test_the_taps_log_every_form_of_call(monkeypatch):
    """The taps (sim/_inputs.c) log each form of call as expected, and the simulator's method is called with
    the same arguments (the same results)."""
    from simatch.sim import inputs as world

    sim = Simulator(simatch.Simulation("msl_5v5").scene.spec)
    sim.inputs = None
    log = world.InputLog()
    sim.inputs = log
    assert type(sim.__dict__["command_velocity"]).__name__ == "Tap"
    results = []
    for name, args, kwargs in CALLS:
        try:
            results.append(getattr(sim, name)(*args, **kwargs))
        except Exception as exc:
            results.append(type(exc).__name__)
    msg = log.take(0.0, 0, False)
    entries = (msg.kind.tolist(), msg.robot.tolist(), [str(v) for v in msg.values.tolist()], list(msg.calls))
    assert results == [
        True,
        True,
        False,
        False,
        True,
        True,
        True,
        True,
        True,
        True,
        True,
        True,
        True,
        True,
        True,
        False,
    ]
    assert entries == (
        [1, 1, 1, 1, 3, 3, 3, 3, 2, 2, 2, 2, 2, 2, 3, 2],
        [0, 1, 2, 3, -1, -1, -1, -1, 0, 1, 2, 3, 3, 4, -1, 0],
        [
            *("0.5", "-0.25", "0.125", "0.10000000149011612", "1.0", "1.0", "nan", "0.0", "0.0", "nan", "0.0", "0.0"),
            *("1.0", "0.0", "0.0", "nan", "0.0", "3.5", "0.0", "nan", "1.0", "2.0", "1.0", "nan"),
            *("1.0", "1.0", "0.0", "0.3", "1.0", "1.0", "0.0", "nan", "0.0", "2.0", "1.0", "nan"),
            *("1.0", "nan", "0.0", "nan"),
        ],
        [
            '["command_velocity", [0, 0.1, 0.2, 0.3, 0.0], {}]',
            '["command_velocity", [0, 0.1, 0.2], {"w": 0.3}]',
            '["command_velocity", [1, 0.1, 0.2, 0.3], {}]',
            '["command_velocity", [true, 0.1, 0.2, 0.3], {}]',
            '["command_action", [0, true], {"kick_speed": 1.0}]',
        ],
    )
    assert log.take(0.0, 1, False) is None  # taken: the log is empty, its lists are still the taps' lists
    sim.command_velocity(0, 1.0, 0.0, 0.0)
    assert log.take(0.0, 1, False).kind.tolist() == [VEL]


class _TextCommands(Node):
    """Sends cyan/2 a speed written as text ("1.5") every tick, and a good command to cyan/3: the simulator
    refuses the text, so the log must not record it as the number it reads as."""

    phase = Phase.ROBOT
    name = "test/text_commands"

    def __init__(self, sim):
        self.sim, self.period = sim, sim.scene.spec.control.period

    def tick(self, now: float) -> None:
        s = self.sim.simulator
        s.command_velocity(s.index_of("cyan/2"), "1.5", 0.0, 0.0)
        s.command_velocity(s.index_of("cyan/3"), 1.5, 0.0, 0.0)


def test_a_number_written_as_text_is_logged_as_refused(tmp_path):
    from simatch.sim import inputs as world

    log = world.InputLog()

    def command(*args):
        pass

    for form, code, args in (
        ("vel", world.VEL, (0, "1.5", 0.25, np.float32(0.5))),
        ("action", world.ACTION, (1, True, b"2", False)),
    ):
        tap = world.Tap(form, command, command, log, world.InputLog.busy, log.kind, log.robot, log.values, code)
        tap(*args)
    assert [str(v) for v in log.take(0.0, 0, False).values.tolist()] == [
        *("nan", "0.25", "0.5"),
        *("1.0", "nan", "0.0", "nan"),
    ]
    path = tmp_path / "text.mcap"
    overrides = {"judge.kind": "none", "teams.cyan.strategy": "none", "teams.magenta.strategy": "none"}
    with simatch.Simulation("msl_5v5", seed=1, overrides=overrides) as sim:
        with Recorder.for_run(sim, path):
            sim.clock.add(_TextCommands(sim))
            sim.run(seconds=1.0)
            moved = sim.model_states()
            assert sim.simulator.refused[sim.simulator.index_of("cyan/2")] > 0
    start = dict(zip(("x", "y"), simatch.Simulation("msl_5v5").scene.spec.teams["cyan"].start[1][:2]))
    assert abs(moved["cyan/2"].x - start["x"]) < 0.05  # it stood: the text was refused
    assert verify(path).identical


def test_the_inputs_numbers_are_converted_as_numpy_converts_them():
    """The WorldInputs arrays made from the log's lists (in C by `pack`, or by the array module where numpy
    scalars are among them) hold the numbers numpy's constructor makes of the same lists; what is not a
    number is left to the one-by-one conversion."""
    from simatch.sim import inputs as world

    plain = [0.1, -0.0, 2**53 + 1, 2**70, -(2**63) - 1, True, False, 7, math.inf, np.float32(0.1), np.int64(-3)]
    made = world._machine_array(plain, "d", np.float64)
    assert made.dtype == np.float64 and made.flags.writeable
    assert made.tobytes() == np.array(plain).astype(np.float64).tobytes()
    for other in ("1.5", b"2", 2**1100, 1j, None):
        assert world._machine_array([1.0, other], "d", np.float64) is None
    assert world._machine_array([0, 3, 255], "B", np.uint8).tolist() == [0, 3, 255]
    assert world._machine_array([-1, 32767, -32768], "h", np.int16).tolist() == [-1, 32767, -32768]
    for code, bad in (("B", 256), ("B", -1), ("h", 32768), ("h", 1.0)):
        assert world._machine_array([0, bad], code, np.uint8 if code == "B" else np.int16) is None
    assert world.pack([1, 2.5, True], "d") == bytearray(np.array([1.0, 2.5, 1.0]).tobytes())
    assert world.pack([1.0, np.float32(0.1)], "d") is None  # (the array module's)
    with pytest.raises(ValueError):
        world.pack([1], "q")


def test_a_recording_with_sha256_fingerprints_is_verified_with_them(tmp_path, monkeypatch):
    """Recordings of format 1 took the fingerprints as SHA-256's (and did not say so: read as SHA-256); a
    re-simulation takes them the same way."""
    import types

    import simatch.record.recorder as recorder
    from simatch.record.reproduce import _fingerprint_kind

    path = tmp_path / "sha.mcap"
    monkeypatch.setattr(recorder, "_fingerprint_kind", lambda: "sha256")
    with simatch.Simulation("msl_5v5", seed=3) as sim:
        sim.simulator.fingerprint_kind = "sha256"
        with Recorder.for_run(sim, path):
            sim.run(seconds=0.6)
    assert Recording(path).metadata["fingerprint"] == "sha256"
    for mode in ("inputs", "strategies"):
        verdict = verify(path, mode=mode)
        assert verdict.identical and verdict.compared == 120, (mode, verdict.first_difference)
    assert _fingerprint_kind(types.SimpleNamespace(metadata={}, path=path)) == "sha256"


def test_fingerprints_of_an_unknown_kind_are_refused(tmp_path, monkeypatch):
    import simatch.record.recorder as recorder

    path = tmp_path / "future.mcap"
    monkeypatch.setattr(recorder, "_fingerprint_kind", lambda: "blake3")
    with simatch.Simulation("omni_circle", seed=2) as sim:
        with Recorder.for_run(sim, path):
            sim.run(seconds=0.2)
    with pytest.raises(VerifyError, match="taken as 'blake3', which this simatch"):
        verify(path)


def test_a_tap_reads_the_busy_mark_only_through_the_logs_own_slot():
    """The taps read ``busy`` where the member descriptor handed to them reads it (``InputLog.busy``); anything
    else is refused when the tap is made, never read at a guessed offset."""
    from simatch.sim import inputs as world

    log = world.InputLog()

    def command(*args):
        return args

    def tap(busy, of=log):
        return world.Tap("vel", command, command, of, busy, log.kind, log.robot, log.values, world.VEL)

    class Other:
        __slots__ = ("busy",)

    for wrong, of in ((Other.busy, log), (world.InputLog.kind, object()), (property(lambda s: False), log)):
        with pytest.raises(TypeError, match="InputLog.busy"):
            tap(wrong, of)
    logged = tap(world.InputLog.busy)
    assert logged(0, 1.0, 2.0, 3.0) == (0, 1.0, 2.0, 3.0) and log.kind == [world.VEL]
    log.busy = True  # inside a logged call: what it calls in turn is not logged again
    assert logged(1, 1.0, 2.0, 3.0) == (1, 1.0, 2.0, 3.0) and log.kind == [world.VEL]
