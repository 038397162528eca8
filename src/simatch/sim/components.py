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

from ..compiled import Array, Bool, Int, bind, kernel
from .kernels import Words, mix64

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


@kernel
def _bytes(flags):
    """`mix64` of bytes (each one a word)."""
    words = np.empty(flags.size, np.uint64)
    for i in range(flags.size):
        words[i] = flags[i]
    return mix64(words)


@kernel
def _row(block, cursor):
    """The row of the step under way (the last one begun; the last row again if the block is full)."""
    return min(cursor[0], block.shape[0]) - 1


@kernel(
    block=_Block, cursor=_Cursor, start=Words, qpos=Words, qvel=Words, act=Words, cmd=Words, aerial=Words,
    usable=_Flags, parts=Words,
)  # fmt: skip
def take_inputs(block, cursor, start, qpos, qvel, act, cmd, aerial, usable, parts):
    """A step begins: its row (``start``: the constants' fingerprints, 0 for the rest) and the fingerprint of
    the world as it takes it (`COMPONENTS`); ``cursor``: the rows begun since the last take, and whether the
    block overflowed."""
    row = cursor[0]
    if row >= block.shape[0]:
        row = block.shape[0] - 1
        cursor[1] = 1
    else:
        cursor[0] = row + 1
    block[row, :] = start
    parts[0] = mix64(qpos)
    parts[1] = mix64(qvel)
    parts[2] = mix64(act)
    parts[3] = mix64(cmd)
    parts[4] = mix64(aerial)
    parts[5] = _bytes(usable)
    block[row, INPUTS] = mix64(parts)


@kernel(
    block=_Block, cursor=_Cursor, ctrl=Words, ground=Int, biasprm=_Block, ball_q=Words, ball_v=Words,
    eq_data=_Block, eq_active=_Flags, xfrc=Words, aerial=Bool, gather=Words, parts=Words, wrenched=Bool,
)  # fmt: skip
def take_before_physics(
    block, cursor, ctrl, ground, biasprm, ball_q, ball_v, eq_data, eq_active, xfrc, aerial, gather, parts, wrenched
):
    """What the drive, ball handling, the applied forces and the flight controller wrote, before MuJoCo's step:
    each writes its own part of the engine's arrays, so one call takes them all: the drive the ground servos'
    rates (the first ``ground`` words of ctrl) and constant bias forces (their biasprm's first column), ball
    handling the ball's state and the dribble constraints (which are on, their anchors: eq_data's first six
    columns), the applied forces xfrc_applied, the flight controller the rest of ctrl."""
    row = _row(block, cursor)
    parts[0] = mix64(ctrl[:ground])
    for i in range(ground):
        gather[i] = biasprm[i, 0]
    parts[1] = mix64(gather[:ground])
    block[row, DRIVE] = mix64(parts[:2])
    parts[0] = mix64(ball_q)
    parts[1] = mix64(ball_v)
    n = 0
    for e in range(eq_data.shape[0]):
        for j in range(6):
            gather[n] = eq_data[e, j]
            n += 1
    parts[2] = mix64(gather[:n])
    parts[3] = _bytes(eq_active)
    block[row, BALL] = mix64(parts[:4])
    if wrenched:
        block[row, FORCES] = mix64(xfrc)
    if aerial:
        block[row, FLIGHT] = mix64(ctrl[ground:])


@kernel(block=_Block, cursor=_Cursor, slot=Int, a=Words, b=Words, c=Words, e=Words, parts=Words)
def take_after(block, cursor, slot, a, b, c, e, parts):
    """The fingerprint of what MuJoCo's step or the ball's bounce left (qpos, qvel, and for the step act and
    the solver's warm start) into the step's row at ``slot``."""
    parts[0] = mix64(a)
    parts[1] = mix64(b)
    parts[2] = mix64(c)
    parts[3] = mix64(e)
    block[_row(block, cursor), slot] = mix64(parts[:4])


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
    applied), `physics` after it and `bounce` after a bounce: each is one compiled call on the arrays, bound
    here once."""

    def __init__(self, sim, capacity: int = CAPACITY):
        m, d = sim.m, sim.d
        self.first = sim.step_index  # the step of the first row not yet taken
        self._block = np.zeros((capacity, len(COMPONENTS)), dtype=np.uint64)
        self._cursor = np.zeros(2, dtype=np.int64)
        parts = np.zeros(6, dtype=np.uint64)
        # every row starts with the constants' fingerprints (taken once: nothing changes them while stepping)
        start = np.zeros(len(COMPONENTS), dtype=np.uint64)
        start[ENGINE] = constants([getattr(m, name) for name in ENGINE_CONSTANTS])
        drive, fleet = sim.drive, sim.aerial
        start[DRIVE_CONSTANTS] = constants([drive.M, drive.Mpinv, drive.max_speed, drive.up, drive.down])
        if fleet is not None:
            start[FLIGHT_CONSTANTS] = constants([fleet.mix, fleet.P.view(np.float64), fleet.limits])
        self._start = start
        qpos, qvel, act, ctrl = _words(d.qpos), _words(d.qvel), _words(d.act), _words(d.ctrl)
        aerial = _words(fleet.cmd) if fleet is not None else np.zeros(0, dtype=np.uint64)
        block, cursor = self._block, self._cursor
        self.inputs = partial(
            bind(take_inputs), block, cursor, start, qpos, qvel, act, _words(drive.cmd), aerial,
            sim.usable.view(np.uint8), parts,
        )  # fmt: skip
        b, bv = sim.engine.ball_q, sim.engine.ball_v
        gather = np.zeros(3 * sim.ng + 6 * m.neq, dtype=np.uint64)
        self.before_physics = partial(
            bind(take_before_physics), block, cursor, ctrl, 3 * sim.ng, m.actuator_biasprm.view(np.uint64),
            _words(d.qpos[b : b + 7]), _words(d.qvel[bv : bv + 6]), m.eq_data.view(np.uint64),
            d.eq_active.view(np.uint8), _words(d.xfrc_applied), fleet is not None, gather, parts,
        )  # fmt: skip
        after = bind(take_after)
        self.physics = partial(after, block, cursor, PHYSICS, qpos, qvel, act, _words(d.qacc_warmstart), parts)
        none = np.zeros(0, dtype=np.uint64)
        self.bounce = partial(after, block, cursor, BOUNCE, qpos, qvel, none, none, parts)

    def take(self) -> tuple[int, np.ndarray]:
        """The first step and the rows (steps x components, flat) since the last take, and forget them."""
        if self._cursor[1]:
            raise RuntimeError(
                f"more than {len(self._block)} steps' component fingerprints were not taken: take them more often"
            )
        n = int(self._cursor[0])
        first, rows = self.first, self._block[:n].ravel().copy()
        self.first += n
        self._cursor[0] = 0
        return first, rows
