"""Per-component fingerprints of every physics step: what each part of the world's pipeline produced.

A re-simulation that drifts from its recording (another CPU, another C library, another Python) drifts first
in one part of the step. To name it, a recorded run keeps, for every physics step, a 64-bit fingerprint
(`simatch.sim.kernels.mix64`, the one hash of the exact states) of what each component wrote, in the order
they run (`COMPONENTS`):

``engine model``
    what MuJoCo computed when it compiled the world (masses, inertias, their frames, the bodies' and dofs'
    inverse weights, bounding volumes, actuators' reference accelerations): the same in every row;
``drive constants``
    what simatch computed when it built the ground robots' drives: the wheel matrices, their pseudo-inverses
    (`numpy.linalg.pinv`, by LAPACK) and the wheel limits: the same in every row;
``flight constants``
    what it computed when it built the drones: their mixers (`numpy.linalg` again), parameters and limits: the
    same in every row (0 in a world without drones);
``inputs``
    the world as the step takes it: the engine's state (qpos, qvel, act) after the placements, teleports and
    drive resets made between steps, the commands after intake and the watchdog, who may move;
``drive``
    the wheel planning's output: the base servos' rates (ctrl) and biases (biasprm) the engine integrates;
``ball handling``
    the dribbler's and the kicker's writes: the ball's velocity, the dribble constraints and their anchors;
``applied forces``
    the wrenches applied through the world services (0 on a step without any);
``flight controller``
    the aerial robots' rotor commands (0 in a world without them);
``world physics``
    MuJoCo's ``mj_step``: qpos, qvel, act and the solver's warm start after it;
``ball bounce``
    the analytic bounce of a ball that met the floor during the step (0 on a step without one).

So the first component whose fingerprint differs at the first step that differs is where the drift starts,
since the step before ended with the same state. Nothing here runs unless somebody listens to
``component_fingerprints`` (a recorder): the simulator's ``prints`` is None then and its step only checks
that.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from numba.core import types
from numba.experimental import structref

from ..compiled import Array, Bool, Int, bind, kernel
from .kernels import Words, mix64, mix_begin, mix_end, mix_word

#: the components in pipeline order (the ComponentFingerprints message names them the same)
COMPONENTS = (
    "engine model",
    "drive constants",
    "flight constants",
    "inputs",
    "drive",
    "ball handling",
    "applied forces",
    "flight controller",
    "world physics",
    "ball bounce",
)
ENGINE, DRIVE_CONSTANTS, FLIGHT_CONSTANTS, INPUTS, DRIVE, BALL, FORCES, FLIGHT, PHYSICS, BOUNCE = range(len(COMPONENTS))
#: what each component is, for a verdict
DESCRIPTIONS = {
    "engine model": "the engine's model (what MuJoCo computed when it compiled the world)",
    "drive constants": "the drives' constants (wheel matrices and their pseudo-inverses, limits)",
    "flight constants": "the drones' constants (mixers, parameters, limits)",
    "inputs": "the world's inputs (commands after intake and the watchdog, placements)",
    "drive": "the drive (wheel planning: the servos' rates and biases)",
    "ball handling": "ball handling (dribbler, kicker)",
    "applied forces": "applied forces (world services' wrenches)",
    "flight controller": "the flight controller (rotor commands)",
    "world physics": "world physics (MuJoCo mj_step)",
    "ball bounce": "the ball's bounce (simatch's analytic impact)",
    "perception": "perception (what the robots were told)",
    "strategies": "a strategy (the commands the robots sent)",
    "referee": "the referee (game state, coach commands)",
}
_Flags = Array(np.uint8, 1)
_Block = Array(np.uint64, 2)
_Cursor = Array(np.int64, 1)
#: the engine model's arrays that MuJoCo computes when it compiles a world, and that nothing changes after
ENGINE_CONSTANTS = (
    "body_mass",
    "body_subtreemass",
    "body_inertia",
    "body_ipos",
    "body_iquat",
    "body_invweight0",
    "dof_invweight0",
    "dof_M0",
    "geom_rbound",
    "geom_aabb",
    "actuator_acc0",
    "actuator_length0",
)
#: rows kept between two takes (a recorder takes them every control tick)
CAPACITY = 4096


@structref.register
class _SourcesType(types.StructRef):
    """numba's type of `Sources`."""

    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(t)) for name, t in fields)


class Sources(structref.StructRefProxy):
    """What the fingerprints read (the engine's and the drive's arrays, as 64-bit words: the same memory) and
    where they write (``block``: a row per step; ``cursor``: the rows begun since the last take, and whether
    the block overflowed), in one object, so that each compiled call takes one argument: numba unboxes every
    array argument at every call, and with the arrays passed one by one (29 per step) the calls cost a
    recorded match 4.8 us per step instead of 3.4."""


#: the fields of `Sources` and their types (the engine's arrays are views of its memory, not copies)
SOURCES = (
    ("block", _Block),
    ("cursor", _Cursor),
    ("start", Words),  # a row's first values: the constants' fingerprints, 0 for the rest
    ("qpos", Words),
    ("qvel", Words),
    ("act", Words),
    ("cmd", Words),  # the drives' commanded twists
    ("aerial", Words),  # the drones' commands (empty without drones)
    ("usable", _Flags),  # who may move
    ("ctrl", Words),
    ("ground", Int),  # the ground servos' share of ctrl (3 per ground robot); the rest is the drones'
    ("biasprm", _Block),
    ("ball_q", Int),  # the ball's first word in qpos, and in qvel
    ("ball_v", Int),
    ("eq_data", _Block),
    ("eq_active", _Flags),
    ("xfrc", Words),
    ("warmstart", Words),
    ("has_aerial", Bool),
)
structref.define_boxing(_SourcesType, Sources)
_Sources = _SourcesType(list(SOURCES))


@kernel(**dict(SOURCES))
def _sources(
    block, cursor, start, qpos, qvel, act, cmd, aerial, usable, ctrl, ground, biasprm, ball_q, ball_v, eq_data,
    eq_active, xfrc, warmstart, has_aerial,
):  # fmt: skip
    """A `Sources` of these arrays (in `SOURCES`' order)."""
    s = structref.new(_Sources)
    s.block, s.cursor, s.start = block, cursor, start
    s.qpos, s.qvel, s.act, s.cmd, s.aerial, s.usable = qpos, qvel, act, cmd, aerial, usable
    s.ctrl, s.ground, s.biasprm, s.ball_q, s.ball_v = ctrl, ground, biasprm, ball_q, ball_v
    s.eq_data, s.eq_active, s.xfrc, s.warmstart, s.has_aerial = eq_data, eq_active, xfrc, warmstart, has_aerial
    return s


@kernel
def _bytes(flags):
    """`mix64` of bytes (each one a word)."""
    h = mix_begin(flags.size)
    for f in flags:
        h = mix_word(h, np.uint64(f))
    return mix_end(h)


@kernel
def _row(s):
    """The row of the step under way (the last one begun; the last row again if the block is full)."""
    return min(s.cursor[0], s.block.shape[0]) - 1


@kernel(s=_Sources)
def take_inputs(s):
    """A step begins: its row (the constants' fingerprints, 0 for the rest) and the fingerprint of the world
    as it takes it (`COMPONENTS`)."""
    block, cursor = s.block, s.cursor
    row = cursor[0]
    if row >= block.shape[0]:
        row = block.shape[0] - 1
        cursor[1] = 1
    else:
        cursor[0] = row + 1
    block[row, :] = s.start
    block[row, INPUTS] = mix64(
        (mix64(s.qpos), mix64(s.qvel), mix64(s.act), mix64(s.cmd), mix64(s.aerial), _bytes(s.usable))
    )


@kernel(s=_Sources, wrenched=Bool)
def take_before_physics(s, wrenched):
    """What the drive, ball handling, the applied forces and the flight controller wrote, before MuJoCo's step:
    each writes its own part of the engine's arrays, so one call takes them all: the drive the ground servos'
    rates (the first ``ground`` words of ctrl) and constant bias forces (their biasprm's first column), ball
    handling the ball's state and the dribble constraints (which are on, their anchors: eq_data's first six
    columns), the applied forces xfrc_applied (when ``wrenched``), the flight controller the rest of ctrl."""
    block, ground, row = s.block, s.ground, _row(s)
    h = mix_begin(ground)
    for i in range(ground):
        h = mix_word(h, s.biasprm[i, 0])
    block[row, DRIVE] = mix64((mix64(s.ctrl[:ground]), mix_end(h)))
    eq = s.eq_data
    h = mix_begin(6 * eq.shape[0])
    for e in range(eq.shape[0]):
        for j in range(6):
            h = mix_word(h, eq[e, j])
    q, v = s.ball_q, s.ball_v
    block[row, BALL] = mix64((mix64(s.qpos[q : q + 7]), mix64(s.qvel[v : v + 6]), mix_end(h), _bytes(s.eq_active)))
    if wrenched:
        block[row, FORCES] = mix64(s.xfrc)
    if s.has_aerial:
        block[row, FLIGHT] = mix64(s.ctrl[ground:])


@kernel(s=_Sources)
def take_physics(s):
    """The fingerprint of what MuJoCo's step left: qpos, qvel, act and the solver's warm start."""
    s.block[_row(s), PHYSICS] = mix64((mix64(s.qpos), mix64(s.qvel), mix64(s.act), mix64(s.warmstart)))


@kernel(s=_Sources)
def take_bounce(s):
    """The fingerprint of what the ball's bounce left: qpos and qvel."""
    empty = mix64(s.act[:0])
    s.block[_row(s), BOUNCE] = mix64((mix64(s.qpos), mix64(s.qvel), empty, empty))


def _words(array: np.ndarray) -> np.ndarray:
    """The 64-bit words of an engine array (the same memory, flat)."""
    if array.size == 0:
        return np.zeros(0, dtype=np.uint64)
    flat = array.reshape(-1)
    if not np.shares_memory(flat, array):
        raise ValueError("a component's array is not contiguous: its fingerprint would hash a copy")
    return flat.view(np.uint64)


def constants(arrays: list[np.ndarray]) -> int:
    """One fingerprint of constant float64 arrays (their numbers one after the other)."""
    words = [np.ascontiguousarray(a, dtype=np.float64).ravel().view(np.uint64) for a in arrays]
    return int(mix64(np.concatenate(words))) if words else 0


class ComponentPrints:
    """The component fingerprints of the steps of ``sim`` (a `Simulator`) since the last `take`. The simulator's
    step calls `inputs` as it begins, `before_physics` before MuJoCo's step (with whether wrenches were
    applied), `physics` after it and `bounce` after a bounce: each is one compiled call on the `Sources`
    made here once."""

    def __init__(self, sim, capacity: int = CAPACITY):
        m, d = sim.m, sim.d
        self.first = sim.step_index  # the step of the first row not yet taken
        self._block = np.zeros((capacity, len(COMPONENTS)), dtype=np.uint64)
        self._cursor = np.zeros(2, dtype=np.int64)
        self._counts = memoryview(self._cursor)  # the cursor's items as Python ints (cheaper than NumPy's scalars)
        # every row starts with the constants' fingerprints (taken once: nothing changes them while stepping)
        start = np.zeros(len(COMPONENTS), dtype=np.uint64)
        start[ENGINE] = constants([getattr(m, name) for name in ENGINE_CONSTANTS])
        drive, fleet = sim.drive, sim.aerial
        start[DRIVE_CONSTANTS] = constants([drive.M, drive.Mpinv, drive.max_speed, drive.up, drive.down])
        if fleet is not None:
            start[FLIGHT_CONSTANTS] = constants([fleet.mix, fleet.P.view(np.float64), fleet.limits])
        aerial = _words(fleet.cmd) if fleet is not None else np.zeros(0, dtype=np.uint64)
        self._sources = bind(_sources)(
            self._block, self._cursor, start, _words(d.qpos), _words(d.qvel), _words(d.act), _words(drive.cmd),
            aerial, sim.usable.view(np.uint8), _words(d.ctrl), 3 * sim.ng, m.actuator_biasprm.view(np.uint64),
            sim.engine.ball_q, sim.engine.ball_v, m.eq_data.view(np.uint64), d.eq_active.view(np.uint8),
            _words(d.xfrc_applied), _words(d.qacc_warmstart), fleet is not None,
        )  # fmt: skip
        sources = self._sources
        self.inputs = partial(bind(take_inputs), sources)
        self.before_physics = partial(bind(take_before_physics), sources)
        self.physics = partial(bind(take_physics), sources)
        self.bounce = partial(bind(take_bounce), sources)

    def take(self) -> tuple[int, np.ndarray]:
        """The first step and the rows (steps x components, flat) since the last take, and forget them."""
        cursor = self._counts
        if cursor[1]:
            raise RuntimeError(
                f"more than {len(self._block)} steps' component fingerprints were not taken: take them more often"
            )
        n = cursor[0]
        first, rows = self.first, self._block[:n].flatten()
        self.first += n
        cursor[0] = 0
        return first, rows
