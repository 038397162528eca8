"""The world's inputs: everything that enters the simulated world from outside the simulator, logged where it
enters, so that a run can be re-simulated from its inputs alone.

The simulator changes its world only through a few methods (a robot's velocity and action commands, the
Gazebo-like calls, sending a robot off, freezing it); each is marked `world_input`, which is the one place
where inputs are logged: whoever calls them — the bus adapter with the commands a team sent (after the
server's checks, at the step the server hands them over), a referee placing the ball, a web operator, a
script through the Python API, a plug-in with its own randomness — the call is logged as it is made, in
order, with the step it acts on. Calls the simulator makes itself (the watchdog stopping a robot, a
placement releasing the held ball) are not inputs: they follow from the logged ones.

While the log is on (`Simulator.inputs`), the bus adapter publishes each step's inputs as one `WorldInputs`
message on ``world_inputs``: those made between two steps before the step's states go out (in the SENSE
phase, ``before_sense``), the rest just before the physics (in the ACT phase). `WorldReplay` carries them
out on a fresh simulator of the same scene, in the same order at the same steps, and the world follows bit
for bit: MuJoCo is deterministic for the same calls, and nothing else changes the world (perception, its
noise and the referee only read it).

While the log is off, a marked method is the plain one. While it is on, the velocity and action commands (what
a match sends most) are replaced by taps written in C (``Tap``, sim/_inputs.c, built by ``pip install -e .``),
which append the command to the log's lists in the compact form and call the method; every other marked
method, and a command in another form, is logged as a call (`_logged_call`).
"""

from __future__ import annotations

import functools
import json
import math
from array import array
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import msgs

try:
    from ._inputs import Tap, pack
except ImportError as exc:  # (a checkout where the extension was not built, or was built for another Python)
    raise msgs.unbuilt("simatch.sim._inputs", exc) from exc

VEL, ACTION, CALL = msgs.WorldInputs.VEL, msgs.WorldInputs.ACTION, msgs.WorldInputs.CALL
#: the Simulator methods marked as world inputs (what a CALL input may name)
METHODS: set[str] = set()

_WorldInputs = msgs.positional(msgs.WorldInputs, "stamp step before_sense kind robot values calls")


class InputError(ValueError):
    """A recorded input that cannot be carried out (it names no input of the simulator, or is malformed)."""


def _number(value: Any) -> float:
    """A command's number as float64, exactly; what is not a number becomes NaN (the simulator refuses both).
    Text is not a number even when it reads as one: the simulator refuses ``"1.5"`` (it does not compare with
    a float), so the log must not turn it into a command that a replay would carry out."""
    if isinstance(value, str | bytes | bytearray):
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan
    except OverflowError:  # an int beyond float64: refused as absurd all the same
        return math.inf if value > 0 else -math.inf


def _machine_array(items: list, code: str, dtype) -> np.ndarray | None:
    """``items`` (Python numbers) as a numpy array of ``dtype`` (array module ``code``: "d", "B" or "h"), converted
    as numpy's constructor converts them; None if some item is not a number. Exact ints, floats and bools are
    packed in C (`pack`); a list with other numbers (numpy scalars) goes through the array module."""
    data = pack(items, code)
    if data is None:
        try:
            data = array(code, items)
        except (TypeError, ValueError, OverflowError):
            return None
    return np.frombuffer(data, dtype=dtype)


def _plain(value: Any) -> Any:
    """JSON for what the API takes besides plain numbers: numpy arrays and scalars exactly, tuples as lists."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if isinstance(value, tuple | set | frozenset):
        return list(value)
    return repr(value)  # never fails the caller; the simulator refuses such values anyway


class InputLog:
    """The inputs of the current physics step, in order (see the module's docstring).

    Three lists hold the inputs: ``kind`` (VEL, ACTION or CALL), ``robot`` (the robot's index; -1 for a call)
    and ``values``, the numbers of the compact forms as given (made float64, exactly, when the message is
    built): VEL ``vx, vy, w``; ACTION ``dribble`` (1.0 or 0.0), ``kick_speed``, ``lob`` (1.0 or 0.0),
    ``window`` (NaN: none). The taps append to these very lists, and read ``busy`` in its slot (the member
    descriptor ``InputLog.busy`` is handed to them)."""

    __slots__ = ("busy", "kind", "robot", "values", "calls")

    def __init__(self):
        self.busy = False  # inside a logged call: what it calls in turn follows from it
        self.kind: list[int] = []
        self.robot: list[int] = []
        self.values: list[float] = []
        self.calls: list[str] = []

    def call(self, name: str, args: tuple, kwargs: dict) -> None:
        self.kind.append(CALL)
        self.robot.append(-1)
        self.calls.append(json.dumps([name, list(args), kwargs], default=_plain))

    def __len__(self) -> int:
        return len(self.kind)

    def take(self, stamp: float, step: int, before_sense: bool):
        """The logged inputs as a WorldInputs message (None if there are none), and a fresh log."""
        if not self.kind:
            return None
        # plain numbers as float64, exactly; anything else (text, which must not be read as a number, huge ints,
        # objects) one by one as the simulator took them
        values = _machine_array(self.values, "d", np.float64)
        if values is None:
            values = np.array([_number(v) for v in self.values], dtype=np.float64)
        kinds, robots = _machine_array(self.kind, "B", np.uint8), _machine_array(self.robot, "h", np.int16)
        if kinds is None or robots is None:  # (not met: the log appends its own codes and robot indices only)
            kinds, robots = np.array(self.kind, dtype=np.uint8), np.array(self.robot, dtype=np.int16)
        msg = _WorldInputs(
            stamp,
            step,
            before_sense,
            kinds,
            robots,
            values,
            self.calls,
        )
        self.clear()
        return msg

    def clear(self) -> None:
        """Empty the log. Its lists stay the same objects (the taps append to them); the calls are handed to the
        message, so they are a new list."""
        self.kind.clear()
        self.robot.clear()
        self.values.clear()
        self.calls = []


#: the marked methods: name -> how a call is logged ("call", or the compact "vel" and "action")
_MARKED: dict[str, str] = {}


def world_input(method: Callable | None = None, *, form: str = "call") -> Callable:
    """Mark a Simulator method as a way into the world. Marking costs nothing: while the simulator's input log
    is off the method is the plain one; `install` puts a logging twin of each marked method on a simulator
    whose log is on (every call of it from outside the simulator is then logged before it is carried out, and
    the calls it makes in turn are not)."""

    def mark(method: Callable) -> Callable:
        _MARKED[method.__name__] = form
        METHODS.add(method.__name__)
        return method

    return mark(method) if method is not None else mark


def install(sim, log: InputLog | None) -> None:
    """Log the inputs of ``sim`` into ``log`` from now on (None: stop logging)."""
    for name, form in _MARKED.items():
        if log is None:
            sim.__dict__.pop(name, None)
        else:
            original = getattr(type(sim), name).__get__(sim)
            sim.__dict__[name] = _LOGGERS[form](original, name, log)


def _logged_call(original: Callable, name: str, log: InputLog) -> Callable:
    @functools.wraps(original)
    def entry(*args, **kwargs):
        if log.busy:
            return original(*args, **kwargs)
        log.busy = True
        try:
            log.call(name, args, kwargs)
            return original(*args, **kwargs)
        finally:
            log.busy = False

    return entry


def _tap(form: str, code: int) -> Callable:
    def logged(original: Callable, name: str, log: InputLog) -> Callable:
        """A tap (sim/_inputs.c): the command logged in the compact form ``form``, anything else as a call."""
        general = _logged_call(original, name, log)
        return Tap(form, original, general, log, InputLog.busy, log.kind, log.robot, log.values, code)

    return logged


_LOGGERS = {"call": _logged_call, "vel": _tap("vel", VEL), "action": _tap("action", ACTION)}
velocity_input = world_input(form="vel")
action_input = world_input(form="action")


class WorldReplay:
    """Re-simulates a world from its recorded inputs: `apply` each step's WorldInputs in recorded order,
    `advance_to` a step to run the physics (and the watchdog) up to it, as the run's physics node did.

    ``sim`` is a fresh `Simulator` of the recorded scene (with its input log off)."""

    def __init__(self, sim):
        self.sim = sim
        sim.inputs = None
        self.applied = 0  # inputs carried out
        self.refused = 0  # of which the simulator refused (as it did in the run: an input is logged before)

    def advance_to(self, step: int) -> None:
        sim = self.sim
        while sim.step_index < step:
            sim.advance()
            sim.events.clear()

    def apply(self, msg) -> None:
        """Carry out one step's inputs (the simulator must be at that step)."""
        sim = self.sim
        if int(msg.step) != sim.step_index:
            raise InputError(f"inputs of step {msg.step} given at step {sim.step_index}")
        kinds, robots, values, calls = msg.kind, msg.robot, msg.values, msg.calls
        need = sum(3 if k == VEL else 4 for k in kinds if k != CALL)
        if len(robots) != len(kinds) or len(values) != need or len(calls) != sum(1 for k in kinds if k == CALL):
            raise InputError(f"the inputs of step {msg.step} are malformed (their arrays do not match)")
        v = values.tolist() if hasattr(values, "tolist") else list(values)
        at = c = 0
        for kind, robot in zip(kinds.tolist() if hasattr(kinds, "tolist") else kinds, list(robots)):
            try:
                if kind == VEL:
                    ok = sim.command_velocity(_robot(sim, robot), v[at], v[at + 1], v[at + 2])
                    at += 3
                elif kind == ACTION:
                    dribble, kick, lob, window = v[at : at + 4]
                    at += 4
                    ok = sim.command_action(
                        _robot(sim, robot), dribble != 0.0, kick, lob != 0.0, None if math.isnan(window) else window
                    )
                elif kind == CALL:
                    text = calls[c]
                    c += 1
                    name, args, kwargs = _parse_call(text, msg.step)
                    getattr(sim, name)(*args, **kwargs)
                    ok = True
                else:
                    raise InputError(f"step {msg.step}: unknown kind of input {kind}")
            except InputError:
                raise
            except Exception:  # refused now as it was then (the simulator's CommandError, a bad argument)
                ok = False
            self.applied += 1
            self.refused += ok is False
        sim.events.clear()


def _robot(sim, index) -> int:
    i = int(index)
    if not 0 <= i < sim.n:
        raise InputError(f"a recorded command names robot {i}, and the scene has {sim.n}")
    return i


def _parse_call(text: str, step: int) -> tuple[str, list, dict]:
    try:
        name, args, kwargs = json.loads(text)
    except (ValueError, TypeError) as exc:
        raise InputError(f"step {step}: a recorded call does not read ({exc})") from None
    if name not in METHODS or not isinstance(args, list) or not isinstance(kwargs, dict):
        raise InputError(f"step {step}: {str(name)[:40]!r} is not an input of the simulator")
    return name, args, kwargs
