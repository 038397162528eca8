"""Per-component fingerprints of every physics step: what each part of the world's pipeline produced.

A re-simulation that drifts from its recording (another CPU, another C library, another Python) drifts first
in one part of the step. To name it, a recorded run keeps, for every physics step, a 64-bit fingerprint
(`simatch.sim.kernels.mix64`, the one hash of the exact states) of what each component wrote, in the order
they run (`COMPONENTS`):

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

import numpy as np

from ..compiled import Array, kernel
from .kernels import Words, mix64

#: the components in pipeline order (the ComponentFingerprints message names them the same)
COMPONENTS = (
    "inputs",
    "drive",
    "ball handling",
    "applied forces",
    "flight controller",
    "world physics",
    "ball bounce",
)
INPUTS, DRIVE, BALL, FORCES, FLIGHT, PHYSICS, BOUNCE = range(len(COMPONENTS))
#: what each component is, for a verdict
DESCRIPTIONS = {
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


@kernel(a=Words, b=Words, c=Words, e=Words, f=Words, flags=_Flags, parts=Words)
def fingerprint_parts(a, b, c, e, f, flags, parts):
    """`mix64` of the `mix64` of each of the arrays ``a`` .. ``f`` (their 64-bit words) and of the bytes
    ``flags``, ``parts`` (6 words) as the scratch."""
    parts[0] = mix64(a)
    parts[1] = mix64(b)
    parts[2] = mix64(c)
    parts[3] = mix64(e)
    parts[4] = mix64(f)
    words = np.empty(flags.size, np.uint64)
    for i in range(flags.size):
        words[i] = flags[i]
    parts[5] = mix64(words)
    return mix64(parts)


def _words(array: np.ndarray) -> np.ndarray:
    """The 64-bit words of an engine array (the same memory, flat)."""
    if array.size == 0:
        return np.zeros(0, dtype=np.uint64)
    flat = array.reshape(-1)
    if not np.shares_memory(flat, array):
        raise ValueError("a component's array is not contiguous: its fingerprint would hash a copy")
    return flat.view(np.uint64)


class ComponentPrints:
    """The component fingerprints of the steps of ``sim`` (a `Simulator`) since the last `take`: `take_step`
    is called by the simulator's step at each component's end."""

    def __init__(self, sim):
        from ..compiled import bind

        m, d = sim.m, sim.d
        self.sim = sim
        self._print = bind(fingerprint_parts)
        self._parts = np.zeros(6, dtype=np.uint64)
        none = np.zeros(0, dtype=np.uint64)
        self._none_flags = np.zeros(0, dtype=np.uint8)
        qpos, qvel, act, ctrl = _words(d.qpos), _words(d.qvel), _words(d.act), _words(d.ctrl)
        aerial = _words(sim.aerial.cmd) if sim.aerial is not None else none
        #: per component: its five word arrays and its flags (bytes)
        self._arrays = [
            (qpos, qvel, act, _words(sim.drive.cmd), aerial, sim.usable.view(np.uint8)),
            (ctrl, _words(m.actuator_biasprm), none, none, none, self._none_flags),
            (qpos, qvel, _words(m.eq_data), none, none, d.eq_active.view(np.uint8)),
            (_words(d.xfrc_applied), none, none, none, none, self._none_flags),
            (ctrl, none, none, none, none, self._none_flags),
            (qpos, qvel, act, _words(d.qacc_warmstart), none, self._none_flags),
            (qpos, qvel, none, none, none, self._none_flags),
        ]
        self.first = sim.step_index  # the step of the first row not yet taken
        self._rows: list[np.ndarray] = []
        self._row = np.zeros(len(COMPONENTS), dtype=np.uint64)

    def take_step(self, component: int) -> None:
        """Fingerprint what ``component`` produced in this step (a component that did not run stays 0)."""
        self._row[component] = self._print(*self._arrays[component], self._parts)

    def end_step(self) -> None:
        """The step is over: its row is kept, the next starts at zeros."""
        self._rows.append(self._row)
        self._row = np.zeros(len(COMPONENTS), dtype=np.uint64)

    def take(self) -> tuple[int, np.ndarray]:
        """The first step and the rows (steps x components, flat) since the last take, and forget them."""
        first, rows = self.first, self._rows
        self.first += len(rows)
        self._rows = []
        flat = np.concatenate(rows) if rows else np.zeros(0, dtype=np.uint64)
        return first, flat
