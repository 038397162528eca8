"""What a learning agent does each control period: a body-frame velocity and the ball handling, as a robot's
Control decides them (VelCmd and ActionCmd), from a `Box` or a small `Discrete` set.

Box action: six float32 numbers in [-1, 1], scaled to the robot model's limits:

===== ========== ===========================================================================================
index name       meaning
===== ========== ===========================================================================================
0     vx         forward speed, x ``max_vel_x`` (the fastest the model's wheels allow straight ahead) [m/s]
1     vy         leftward speed, x ``max_vel_y`` [m/s]
2     w          turn rate (counter-clockwise), x ``max_w`` (the model's on-the-spot limit) [rad/s]
3     dribble    > 0: dribbler on
4     kick       > 0: fire the kicker at ``kick x kicker.max_speed`` when the ball is in the mouth; <= 0: no kick
5     lob        > 0: the kick is a lob (``kicker.lob_angle``), else along the ground
===== ========== ===========================================================================================

The robot then drives as any robot does: the wheel limits (speed, acceleration) of paper Eq. 2-3 and the
drive's servo apply to whatever is commanded. ``max_vel`` and ``max_w`` of the environment scale the
velocity down (e.g. to the 4.5 m/s a referee allows). Numbers outside [-1, 1] are clipped (or refused with
``strict_actions``); NaN, infinities, a wrong shape or a non-number are refused with a ValueError that names
the agent, and the robot's command is left as it was: nothing reaches the physics.

Discrete action: an index into `DISCRETE` (velocities as fractions of the limits above).

An aerial robot (a quadrotor, docs/aerial.md) also climbs: its Box has a seventh number, ``vz`` (upward speed,
x ``max_climb`` up and ``max_descent`` down), and its Discrete set two more moves, ``climb`` and ``descend``
(`AIR_MOVES`); its velocity limits are its controller's (``max_speed``, ``max_yaw_rate``). Its dribbler and
kicker numbers are taken and do nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..strategy import Command

NAMES = ("vx", "vy", "w", "dribble", "kick", "lob")
SIZE = len(NAMES)
#: an aerial robot's Box: the same and its upward speed
AERIAL_NAMES = (*NAMES, "vz")
#: an aerial robot's Discrete moves after `DISCRETE`: (name, vz as a fraction of its climb or descent limit)
AIR_MOVES: tuple[tuple[str, float], ...] = (("climb", 0.5), ("descend", -0.5))

#: (name, vx, vy, w as fractions of the limits, dribble, kick as a fraction of the kicker's speed, lob)
DISCRETE: tuple[tuple[str, float, float, float, bool, float, bool], ...] = (
    ("stop", 0.0, 0.0, 0.0, False, 0.0, False),
    ("forward", 0.5, 0.0, 0.0, False, 0.0, False),
    ("backward", -0.5, 0.0, 0.0, False, 0.0, False),
    ("left", 0.0, 0.5, 0.0, False, 0.0, False),
    ("right", 0.0, -0.5, 0.0, False, 0.0, False),
    ("turn_left", 0.0, 0.0, 0.25, False, 0.0, False),
    ("turn_right", 0.0, 0.0, -0.25, False, 0.0, False),
    ("forward_dribbling", 0.4, 0.0, 0.0, True, 0.0, False),
    ("turn_left_dribbling", 0.0, 0.0, 0.1, True, 0.0, False),
    ("turn_right_dribbling", 0.0, 0.0, -0.1, True, 0.0, False),
    ("kick", 0.0, 0.0, 0.0, True, 1.0, False),
    ("lob", 0.0, 0.0, 0.0, True, 1.0, True),
)


@dataclass(frozen=True)
class Limits:
    """The scales of the action of one robot."""

    max_vel_x: float  # [m/s]
    max_vel_y: float  # [m/s]
    max_w: float  # [rad/s]
    max_kick: float  # [m/s]
    max_lob: float  # [m/s]
    max_climb: float = 0.0  # [m/s]; 0: a ground robot (no vz in its action)
    max_descent: float = 0.0  # [m/s]

    @property
    def aerial(self) -> bool:
        return self.max_climb > 0.0

    @property
    def size(self) -> int:
        """Numbers in this robot's Box action."""
        return len(AERIAL_NAMES) if self.aerial else SIZE

    @property
    def moves(self) -> int:
        """Entries of this robot's Discrete action."""
        return len(DISCRETE) + (len(AIR_MOVES) if self.aerial else 0)

    @classmethod
    def of(cls, model, kicker, max_vel: float | None = None, max_w: float | None = None) -> Limits:
        """From a robot model (its wheel matrix and rim speed limit) and the scene's kicker, optionally
        capped at ``max_vel`` [m/s] and ``max_w`` [rad/s]."""
        for name, cap in (("max_vel", max_vel), ("max_w", max_w)):
            if cap is not None and not (isinstance(cap, int | float) and math.isfinite(cap) and cap > 0):
                raise ValueError(f"{name} must be a positive number, got {cap!r}")
        climb = descent = 0.0
        if getattr(model, "aerial", False):  # its controller's limits
            p = model.params
            vx = vy = p.max_speed
            w, climb, descent = p.max_yaw_rate, p.max_climb, p.max_descent
        else:
            m = np.abs(model.rim_matrix())
            top = model.params.max_wheel_speed
            vx, vy, w = (top / float(m[:, j].max()) for j in range(3))
        if max_vel is not None:
            vx, vy = min(vx, max_vel), min(vy, max_vel)
        if max_w is not None:
            w = min(w, max_w)
        return cls(vx, vy, w, kicker.max_speed, kicker.max_lob_speed, climb, descent)

    def _vz(self, fraction: float) -> float:
        return fraction * (self.max_climb if fraction > 0 else self.max_descent)

    def command(self, a: np.ndarray) -> Command:
        """The Command of a checked Box action (six numbers in [-1, 1])."""
        lob = bool(a[5] > 0)
        kick = float(a[4]) * (self.max_lob if lob else self.max_kick) if a[4] > 0 else 0.0
        return Command(
            vx=float(a[0]) * self.max_vel_x,
            vy=float(a[1]) * self.max_vel_y,
            w=float(a[2]) * self.max_w,
            dribble=bool(a[3] > 0),
            kick_speed=kick,
            lob=lob,
            vz=self._vz(float(a[6])) if len(a) > SIZE else 0.0,
        )

    def discrete(self, index: int) -> Command:
        if index >= len(DISCRETE):  # an aerial robot's climb or descent
            return Command(vz=self._vz(AIR_MOVES[index - len(DISCRETE)][1]))
        _, vx, vy, w, dribble, kick, lob = DISCRETE[index]
        return Command(
            vx=vx * self.max_vel_x,
            vy=vy * self.max_vel_y,
            w=w * self.max_w,
            dribble=dribble,
            kick_speed=kick * (self.max_lob if lob else self.max_kick),
            lob=lob,
        )


def check_box(agent: str, action, strict: bool = False, size: int = SIZE) -> np.ndarray:
    """``action`` as ``size`` float64 numbers in [-1, 1] (six, or seven for an aerial robot); ValueError
    (naming ``agent``) for a wrong shape, a non-number, NaN or infinity, and with ``strict`` for a number
    outside [-1, 1] (else it is clipped)."""
    names = AERIAL_NAMES if size == len(AERIAL_NAMES) else NAMES
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"action of {agent}: expected {size} numbers ({', '.join(names)}), got {action!r}") from None
    if a.shape != (size,):
        raise ValueError(
            f"action of {agent}: expected shape ({size},) ({', '.join(names)}), got shape {a.shape}: {action!r}"
        )
    bad = ~np.isfinite(a)
    if bad.any():
        which = ", ".join(f"{names[i]}={a[i]}" for i in np.flatnonzero(bad))
        raise ValueError(f"action of {agent}: {which} is not a finite number")
    if strict and (np.abs(a) > 1.0).any():
        which = ", ".join(f"{names[i]}={a[i]:g}" for i in np.flatnonzero(np.abs(a) > 1.0))
        raise ValueError(f"action of {agent}: {which} outside [-1, 1]")
    return np.clip(a, -1.0, 1.0)


def check_discrete(agent: str, action, moves: int = len(DISCRETE)) -> int:
    """``action`` as an index of `DISCRETE` (and `AIR_MOVES` after it: ``moves`` in all); ValueError (naming
    ``agent``) for anything else."""
    try:
        a = np.asarray(action)
        if (
            a.shape not in ((), (1,))
            or a.dtype.kind not in "iu"
            and not (a.dtype.kind == "f" and np.all(np.isfinite(a)) and float(a.ravel()[0]).is_integer())
        ):
            raise TypeError
        index = int(a.ravel()[0])
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"action of {agent}: expected an integer in [0, {moves}), got {action!r}") from None
    if not 0 <= index < moves:
        raise ValueError(f"action of {agent}: {index} is not in [0, {moves})")
    return index
