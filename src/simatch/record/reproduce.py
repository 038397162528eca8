"""Reproduction check (``simatch replay FILE --verify``): re-simulate a recorded run and compare.

Two ways, the first one by default:

* **From the recorded inputs** (``--verify``, ``--verify inputs``): the recording holds, for every physics
  step, everything that entered the world from outside the simulator (``world_inputs``: each robot's applied
  commands, placements, forces, robots sent off; see `simatch.sim.inputs`). A fresh simulator of the
  recorded scene is given those inputs at the same steps in the same order, with no strategy, judge or coach,
  and its states are compared with the recorded ones as below. This reproduces any run: embedded or
  distributed, lockstep or real time, with processes killed, late or rejoining, driven by hand from the web
  UI or the referee console, with plug-ins that use their own randomness.
* **From the strategies** (``--verify strategies``): the run's nodes are run again, as the next paragraph
  says. Only a run whose every decision came from deterministic code in the simulator's process reproduces
  so (an embedded run, a lockstep run where no process failed); where it does, it checks the strategies,
  the judge and the coaches too.

The recording holds the scene file's text, the overrides and the seed (metadata) and every intervention
from outside the run's nodes (``operator`` topic: Python API calls, commands given to a coach by hand,
operator actions on a judge). A new embedded `Simulation` of that scene and seed is stepped in lockstep
with the recording; before each physics step the operator commands recorded for that step are applied
again, and the model states the simulator publishes are compared with the recorded ones, byte for byte
(CDR), at every physics step, and so are the fingerprints of the exact float64 states (StateFingerprint,
every control tick): the model states are float32, the fingerprints tell any difference of the
simulator's own numbers. The first step where they differ is reported with the model, the field and both
values. A recording of format 3 on also holds each physics step's component fingerprints (the world's
inputs, the drive, ball handling, ... MuJoCo's step: `simatch.sim.components`); the re-simulation takes them
too, and the verdict names the first step and component that differ (`simatch.record.divergence`); from
the strategies, the run's nodes' messages (perception, the referee's, the strategies') are compared as well,
and one that differs first is named.

Operator commands name what they did (`OperatorCommand.call`): a `Simulation` method of the Python API
(`WORLD_CALLS`), ``coach`` (a command given to ``sim.coaches[target]``), or ``judge.<method>`` for a judge
that lists ``<method>`` in its ``operator_calls`` (how a referee makes its manual actions reproducible).
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import msgs, version
from ..bus import Node, Phase, topics
from ..msgs.cdr import Codec
from . import environment, layout
from .divergence import ComponentCheck, ComponentDifference, DecisionCheck, decision_of, well_formed
from .reader import Recording, RecordingError
from .recorder import TEAM_TOPICS
from .verdict import Difference, Verdict

#: Simulation methods that an operator command may name (called as method(target, **args))
WORLD_CALLS = {
    "set_model_state",
    "set_link_state",
    "apply_wrench",
    "take_control",
    "release_control",
    "send_vel",
    "send_action",
    "set_rotor",
}
POSE_FIELDS = ("x", "y", "z", "qw", "qx", "qy", "qz")
TWIST_FIELDS = ("vx", "vy", "vz", "wx", "wy", "wz")
_STEP = struct.Struct("<4xdQ")  # CDR header, then ModelStates.stamp and .step


class VerifyError(Exception):
    """A recording that cannot be re-simulated (the message says why)."""


def apply_operator(sim, op) -> None:
    """Carry out one recorded operator command on ``sim`` again."""
    try:
        args = json.loads(op.args) if op.args else {}
    except json.JSONDecodeError as exc:
        raise VerifyError(f"operator command {op.call} at t={op.stamp:.3f} s has unreadable arguments: {exc}") from None
    call, target = op.call, op.target
    if call in WORLD_CALLS:
        getattr(sim, call)(target, **args)
    elif call == "coach":
        coach = sim.coaches.get(target)
        if coach is None:
            raise VerifyError(
                f"operator command at t={op.stamp:.3f} s gives a command to the coach of {target!r}, "
                f"which this run does not have"
            )
        cmd = args.pop("cmd")
        coach.send(cmd, **args)
    elif call.startswith("judge."):
        method = call.partition(".")[2]
        if method not in getattr(sim.judge, "operator_calls", ()):
            raise VerifyError(f"operator command {call!r} at t={op.stamp:.3f} s: the judge does not offer it")
        getattr(sim.judge, method)(**args)
    else:
        raise VerifyError(f"unknown operator command {call!r} at t={op.stamp:.3f} s")


#: the ways of re-simulating (``--verify MODE``); "auto": from the inputs where the recording holds them
MODES = ("auto", "inputs", "strategies")


def verify(path: str | Path, progress: Callable[[float], None] | None = None, mode: str = "auto") -> Verdict:
    """Re-simulate the recording at ``path`` and compare its model states step by step: from its recorded
    world inputs (``mode="inputs"``), by running its strategies, judge and coaches again
    (``"strategies"``), or from the inputs where the recording holds them (``"auto"``)."""
    if mode not in MODES:
        raise ValueError(f"unknown verification mode {mode!r}; modes are {', '.join(MODES)}")
    rec = Recording(path)
    meta = rec.metadata
    for key in ("first_step", "seed"):
        try:
            int(meta.get(key, "0"))
        except ValueError:
            raise VerifyError(f"{rec.path}: the recorded {key} {meta.get(key)!r} is not a number") from None
    if not rec.is_simatch:
        raise VerifyError(f"{rec.path} is not a simatch recording (no simatch metadata): nothing to re-simulate")
    if int(meta.get("first_step", "0")) != 0:
        raise VerifyError(
            f"{rec.path}: the recording started at t={int(meta['first_step']) * float(meta['dt']):.3f} s, "
            f"after the run began; a run can only be re-simulated from a recording of its start"
        )
    problems = []
    if meta.get("simatch_version") != version():
        problems.append(
            f"recorded with simatch {meta.get('simatch_version')}, re-simulated with {version()}: "
            f"a different version may simulate differently"
        )
    scene = rec.scene()
    kind = _fingerprint_kind(rec)
    has_inputs = rec.metadata.get("world_inputs") == "1"
    if mode == "inputs" and not has_inputs:
        raise VerifyError(
            f"{rec.path} holds no world inputs (recorded by simatch {meta.get('simatch_version')}, before they were "
            f"recorded, or not from a run's start): try --verify strategies"
        )
    if mode != "strategies" and has_inputs:
        verdict = _verify_inputs(rec, scene, kind, progress)
        verdict.problems = problems + verdict.problems
    else:
        if mode == "auto":
            problems.append("the recording holds no world inputs: re-simulated from its strategies")
        verdict = _verify_strategies(rec, scene, kind, problems, progress)
    verdict.format_version = meta.get("format_version", "")
    verdict.components = holds_components(rec)
    then = environment.recorded(meta)
    if then is not None:
        verdict.environment = environment.differences(then)
    elif not verdict.identical:
        verdict.environment = ["the recording does not say what made it (made before simatch kept that)"]
    return verdict


def holds_components(rec: Recording) -> bool:
    """Whether the recording holds the component fingerprints of its steps (format 3 on)."""
    try:
        return int(rec.metadata.get("format_version", "1")) >= layout.COMPONENTS_SINCE
    except ValueError:
        return False


def _fingerprint_kind(rec: Recording) -> str:
    """How the recording's StateFingerprint messages were taken (its metadata; SHA-256 before it said)."""
    from ..sim.simulator import FINGERPRINTS

    kind = rec.metadata.get("fingerprint", "sha256")
    if kind not in FINGERPRINTS:
        raise VerifyError(
            f"{rec.path}: its state fingerprints were taken as {kind!r}, which this simatch ({version()}) does not "
            f"know (it knows {', '.join(FINGERPRINTS)}): re-simulate it with the simatch that recorded it"
        )
    return kind


def _verify_strategies(rec: Recording, scene, kind: str, problems: list[str], progress) -> Verdict:
    from ..simulation import Simulation  # the embedded run: composes every subsystem

    meta = rec.metadata
    external = [t for t, spec in scene.spec.teams.items() if spec.strategy == "external"]
    if external:
        raise VerifyError(
            f"{rec.path}: team(s) {', '.join(external)} ran outside the simulator process "
            f"(strategy 'external'): their decisions cannot be re-simulated"
        )
    with Simulation(scene, seed=int(meta.get("seed", "0"))) as sim:
        sim.simulator.fingerprint_kind = kind  # its fingerprints as the recording's were taken
        verdict = _compare(rec, sim, problems, progress)
    verdict.mode = "strategies"
    return verdict


def _verify_inputs(rec: Recording, scene, kind: str, progress) -> Verdict:
    """Re-simulate the world alone from the recorded inputs and compare (see the module's docstring)."""
    from ..config.loader import check_models
    from ..sim.components import COMPONENTS, ComponentPrints
    from ..sim.inputs import InputError, WorldReplay
    from ..sim.simulator import Simulator

    check_models(scene)
    sim = Simulator(scene.spec, int(rec.metadata.get("seed", "0")))
    sim.prints = ComponentPrints(sim)
    replay = WorldReplay(sim)
    verdict = Verdict(identical=True, compared=0, until=0.0, mode="inputs")
    check = ComponentCheck(sim.dt)
    holds = holds_components(rec)
    wanted = {topics.MODEL_STATES, topics.STATE_FINGERPRINT, topics.WORLD_INPUTS, topics.COMPONENT_FINGERPRINTS}
    states = _InputStates(rec, sim, replay, kind, verdict, progress)
    try:
        for topic, t_ns, data in rec.raw(topics=wanted):
            if topic == topics.WORLD_INPUTS:
                msg = rec.decode("simatch_msgs/msg/WorldInputs", data, topic)
                if msg is None:
                    raise VerifyError(f"{rec.path}: a world-inputs message does not decode: cannot re-simulate")
                if int(msg.step) < sim.step_index:
                    raise VerifyError(f"{rec.path}: the inputs of step {msg.step} come after that step")
                replay.advance_to(int(msg.step))
                replay.apply(msg)
            elif topic == topics.COMPONENT_FINGERPRINTS:
                msg = _components(rec, data, t_ns, layout.ns(sim.dt))
                if msg is not None:  # (re-simulated through the last step it holds, then compared)
                    rows = len(msg.fingerprint) // len(msg.component)
                    replay.advance_to(max(int(msg.step) + rows, sim.step_index))
                    first, rows = sim.prints.take()
                    check.simulated(first, COMPONENTS, rows)
                verdict.component = check.take(msg)
            elif verdict.first_difference is None:
                states.compare(topic, data)
            # past the first difference of the states, read on until the components of its step are known
            if verdict.first_difference is not None and (not holds or check.settled(verdict.first_difference)):
                break
    except InputError as exc:
        raise VerifyError(f"{rec.path}: {exc}") from None
    if verdict.compared == 0:
        raise VerifyError(f"{rec.path} holds no model states to compare")
    verdict.identical = verdict.first_difference is None and verdict.component is None
    verdict.inputs = replay.applied
    verdict.problems = list(rec.problems)
    verdict.complete = rec.finalised and not rec.problems
    return verdict


class _InputStates:
    """The comparison of the recorded model states and exact states' fingerprints with those of the world
    re-simulated from its inputs (`_verify_inputs`): the first difference goes into the verdict."""

    def __init__(self, rec: Recording, sim, replay, kind: str, verdict: Verdict, progress):
        self.rec, self.sim, self.replay, self.kind = rec, sim, replay, kind
        self.verdict, self.progress = verdict, progress
        self.encode = Codec(msgs.typestore).encode
        self.last_report = -1.0

    def compare(self, topic: str, data) -> None:
        from ..sim.node import fingerprint, model_states_message

        sim, verdict, dt = self.sim, self.verdict, self.sim.dt
        if topic == topics.STATE_FINGERPRINT:
            fp = self.rec.decode("simatch_msgs/msg/StateFingerprint", data, topic)
            if fp is None or int(fp.step) < sim.step_index:
                return
            self.replay.advance_to(int(fp.step))
            _, pose, twist = sim.model_state_arrays()
            mine = fingerprint(pose, twist, self.kind)
            if mine != int(fp.fingerprint):
                verdict.first_difference = _fingerprint_difference(int(fp.step), dt, int(fp.fingerprint), mine)
            return
        _, step = _STEP.unpack_from(data)
        if step < sim.step_index:
            return  # (a second recorder's copy, or out of order: compared once)
        self.replay.advance_to(step)
        names, pose, twist = sim.model_state_arrays()
        mine = model_states_message(step * dt, step, names, pose, twist)
        verdict.compared += 1
        verdict.until = step * dt
        if self.encode(mine) != data:
            verdict.first_difference = _difference(self.rec, bytes(data), mine, dt)
        elif self.progress is not None and verdict.until - self.last_report >= 1.0:
            self.last_report = verdict.until
            self.progress(verdict.until)


class _DuringStep(Node):
    """Applies the operator commands that were made while a step's nodes ran (a viewer's control node),
    at the same point: in the JUDGE phase, after the run's own judge and coaches."""

    phase = Phase.JUDGE
    name = "replay/operator"

    def __init__(self, sim, verdict: Verdict):
        self.sim, self.verdict = sim, verdict
        self.period = sim.dt
        self.due: list = []

    def tick(self, now: float) -> None:
        for op in self.due:
            apply_operator(self.sim, op)
            self.verdict.operator_commands += 1
        self.due = []


def _compare(rec: Recording, sim, problems: list[str], progress) -> Verdict:
    encode = Codec(msgs.typestore).encode
    latest: list = [None]
    verdict = Verdict(identical=True, compared=0, until=0.0)
    during = sim.clock.add(_DuringStep(sim, verdict))
    prints, check, decisions = _Fingerprints(), ComponentCheck(sim.dt), DecisionCheck()
    subs = _listen(sim, latest, prints, check, decisions, encode)
    pending: list = []
    last_report = -1.0
    dt_ns = layout.ns(sim.dt)

    def step_to(step: int) -> None:
        """Advance the re-simulation through physics step ``step`` with the commands recorded for it."""
        while sim.simulator.step_index <= step:
            k = sim.simulator.step_index
            while pending and pending[0].step <= k:
                op = pending.pop(0)
                if op.during_step and op.step == k:
                    during.due.append(op)
                else:
                    apply_operator(sim, op)
                    verdict.operator_commands += 1
            latest[0] = None
            sim.step()

    try:
        # a sample is compared once the next one is read: the commands made during its step come after it
        held: tuple[int, bytes] | None = None
        wanted = {topics.MODEL_STATES, topics.OPERATOR, topics.STATE_FINGERPRINT, topics.COMPONENT_FINGERPRINTS}
        wanted |= {t for t in rec.topics() if decision_of(t) is not None}
        for topic, t_ns, data in rec.raw(topics=wanted):
            if topic == topics.COMPONENT_FINGERPRINTS:
                verdict.component = check.take(_components(rec, data, t_ns, dt_ns))
                if check.settled(verdict.first_difference):
                    break
            elif verdict.first_difference is not None:
                continue  # (past the first difference: only the components of its step are read on)
            elif topic == topics.OPERATOR:
                op = rec.decode("simatch_msgs/msg/OperatorCommand", data, topic)
                if op is not None:
                    pending.append(op)
            elif topic == topics.STATE_FINGERPRINT:
                prints.recorded(rec.decode("simatch_msgs/msg/StateFingerprint", data, topic))
            elif topic != topics.MODEL_STATES:
                decisions.recorded(topic, t_ns // dt_ns, data)
            else:
                _, step = _STEP.unpack_from(data)
                if held is not None and not _check(held, step_to, latest, encode, verdict, rec, sim, prints):
                    held = None
                    _take_unpublished(sim.simulator, check)
                    if not holds_components(rec):
                        break
                    continue
                held = (step, bytes(data)) if step >= sim.simulator.step_index else None
                if progress is not None and verdict.until - last_report >= 1.0:
                    last_report = verdict.until
                    progress(verdict.until)
        if held is not None:
            _check(held, step_to, latest, encode, verdict, rec, sim, prints)
    finally:
        for sub in subs:
            sub.close()
    if verdict.compared == 0:
        raise VerifyError(f"{rec.path} holds no model states to compare")
    _take_unpublished(sim.simulator, check)
    verdict.component = _first_of(check.compare(sim.simulator.step_index - 1), decisions, verdict, sim)
    verdict.identical = verdict.first_difference is None and verdict.component is None
    verdict.problems = problems + rec.problems
    verdict.complete = rec.finalised and not rec.problems
    return verdict


def _listen(sim, latest: list, prints, check: ComponentCheck, decisions: DecisionCheck, encode) -> list:
    """The re-simulation's subscriptions: its model states, fingerprints and its nodes' messages (each at the
    step of the last clock or model states before it, as the recorder times them)."""
    now = [0]

    def states(msg) -> None:
        latest[0] = msg
        now[0] = msg.step

    def decided(topic: str, msg) -> None:
        if decision_of(topic) is not None:
            decisions.simulated(topic, now[0], encode(msg))

    return [
        sim.bus.subscribe(topics.CLOCK, msgs.Clock, lambda m: now.__setitem__(0, m.step)),
        sim.bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, states),
        sim.bus.subscribe(topics.STATE_FINGERPRINT, msgs.StateFingerprint, prints.simulated),
        sim.bus.subscribe(
            topics.COMPONENT_FINGERPRINTS,
            msgs.ComponentFingerprints,
            lambda m: check.simulated(m.step, m.component, m.fingerprint),
        ),
        sim.bus.subscribe_all(TEAM_TOPICS, decided),
        sim.bus.subscribe_all(topics.GAME_STATE, decided),
    ]


def _first_of(component: ComponentDifference | None, decisions: DecisionCheck, verdict: Verdict, sim):
    """The first of the world's components and the run's nodes' messages (perception, referee, strategies)
    that differs. At one step the nodes' come first (their commands are the step's inputs), but after the
    states published at that step: nodes that were told another state did not depart by themselves."""
    diff = verdict.first_difference
    upto = sim.simulator.step_index
    if component is not None:
        upto = component.step
    if diff is not None:
        upto = min(upto, diff.step - 1)
    decided = decisions.first(upto, sim.dt)
    return decided if decided is not None else component


def _components(rec: Recording, data: bytes, t_ns: int, dt_ns: int):
    """A recorded ComponentFingerprints message, or None for one that is damaged (noted among the problems)."""
    msg = rec.decode("simatch_msgs/msg/ComponentFingerprints", data, topics.COMPONENT_FINGERPRINTS)
    if well_formed(msg, t_ns, dt_ns):
        return msg
    note = f"a component-fingerprints message at t={t_ns / layout.NS:.3f} s is damaged: left out of the comparison"
    if note not in rec.problems:
        rec.problems.append(note)
    return None


def _take_unpublished(simulator, check: ComponentCheck) -> None:
    """The re-simulation's component rows not yet published (those of the control period under way)."""
    from ..sim.components import COMPONENTS

    if simulator.prints is not None:
        first, rows = simulator.prints.take()
        check.simulated(first, COMPONENTS, rows)


class _Fingerprints:
    """The exact states' fingerprints (StateFingerprint, every control tick), recorded and re-simulated, by
    physics step: the model states are float32, these tell a difference below float32 too."""

    def __init__(self):
        self.theirs: dict[int, int] = {}
        self.mine: dict[int, int] = {}

    def recorded(self, msg) -> None:
        if msg is not None:
            self.theirs[int(msg.step)] = int(msg.fingerprint)

    def simulated(self, msg) -> None:
        self.mine[int(msg.step)] = int(msg.fingerprint)

    def first_difference(self, upto: int, dt: float) -> Difference | None:
        """Compare every recorded fingerprint up to step ``upto`` (re-simulated by now), then forget them."""
        found = None
        for step in sorted(k for k in self.theirs if k <= upto):
            theirs, mine = self.theirs.pop(step), self.mine.get(step)
            if found is None and theirs != mine:
                found = _fingerprint_difference(step, dt, theirs, "none" if mine is None else mine)
        for step in [k for k in self.mine if k <= upto]:
            del self.mine[step]
        return found


def _fingerprint_difference(step: int, dt: float, theirs: int, mine) -> Difference:
    """The exact states' fingerprints of step ``step`` differ."""
    return Difference(step * dt, step, "(every model)", "fingerprint of the exact states", theirs, mine, 1)


def _check(held, step_to, latest, encode, verdict: Verdict, rec: Recording, sim, prints: _Fingerprints) -> bool:
    """Re-simulate the held sample's step and compare; False at the first difference."""
    step, data = held
    step_to(step)
    mine = latest[0]
    if mine is None:
        raise VerifyError("the re-simulation published no model states")
    verdict.compared += 1
    verdict.until = step * sim.dt
    if encode(mine) != data:
        verdict.identical = False
        verdict.first_difference = _difference(rec, data, mine, sim.dt)
        return False
    differs = prints.first_difference(step, sim.dt)
    if differs is not None:
        verdict.identical = False
        verdict.first_difference = differs
        return False
    return True


def _difference(rec: Recording, data: bytes, mine, dt: float) -> Difference:
    theirs = rec.decode("simatch_msgs/msg/ModelStates", data, topics.MODEL_STATES)
    step = int(theirs.step) if theirs is not None else int(mine.step)
    t = step * dt
    if theirs is None:
        return Difference(t, step, "?", "?", "undecodable", "", 0)
    if list(theirs.name) != list(mine.name):
        return Difference(t, step, "(models)", "name", ", ".join(theirs.name), ", ".join(mine.name), 1)

    # widened to float64 (exact for float32), compared bit for bit (which also tells -0.0 from 0.0)
    def rows(values, fields):
        return np.asarray(values, dtype=float).reshape(-1, len(fields))

    groups = [
        (fields, rows(a, fields), rows(b, fields))
        for fields, a, b in ((POSE_FIELDS, theirs.pose, mine.pose), (TWIST_FIELDS, theirs.twist, mine.twist))
    ]
    diffs = [a.view(np.uint64) != b.view(np.uint64) for _, a, b in groups]
    for (fields, a, b), diff in zip(groups, diffs):
        if diff.any():
            row, col = map(int, np.argwhere(diff)[0])
            total = int(sum(d.sum() for d in diffs))
            return Difference(t, step, theirs.name[row], fields[col], float(a[row, col]), float(b[row, col]), total)
    if theirs.stamp != mine.stamp:
        return Difference(t, step, "(header)", "stamp", theirs.stamp, mine.stamp, 1)
    return Difference(t, step, "(message)", "bytes", "differ", "differ", 0)


__all__ = ["Difference", "RecordingError", "Verdict", "VerifyError", "apply_operator", "verify"]
