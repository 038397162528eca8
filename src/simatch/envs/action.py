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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..strategy import Command

NAMES = ("vx", "vy", "w", "dribble", "kick", "lob")
SIZE = len(NAMES)

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

    @classmethod
    def of(cls, model, kicker, max_vel: float | None = None, max_w: float | None = None) -> Limits:
        """From a robot model (its wheel matrix and rim speed limit) and the scene's kicker, optionally
        capped at ``max_vel`` [m/s] and ``max_w`` [rad/s]."""
        for name, cap in (("max_vel", max_vel), ("max_w", max_w)):
            if cap is not None and not (isinstance(cap, int | float) and math.isfinite(cap) and cap > 0):
                raise ValueError(f"{name} must be a positive number, got {cap!r}")
        m = np.abs(model.rim_matrix())
        top = model.params.max_wheel_speed
        vx, vy, w = (top / float(m[:, j].max()) for j in range(3))
        if max_vel is not None:
            vx, vy = min(vx, max_vel), min(vy, max_vel)
        if max_w is not None:
            w = min(w, max_w)
        return cls(vx, vy, w, kicker.max_speed, kicker.max_lob_speed)

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
        )

    def discrete(self, index: int) -> Command:
        _, vx, vy, w, dribble, kick, lob = DISCRETE[index]
        return Command(
            vx=vx * self.max_vel_x,
            vy=vy * self.max_vel_y,
            w=w * self.max_w,
            dribble=dribble,
            kick_speed=kick * (self.max_lob if lob else self.max_kick),
            lob=lob,
        )


def check_box(agent: str, action, strict: bool = False) -> np.ndarray:
    """``action`` as six float64 numbers in [-1, 1]; ValueError (naming ``agent``) for a wrong shape, a
    non-number, NaN or infinity, and with ``strict`` for a number outside [-1, 1] (else it is clipped)."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"action of {agent}: expected {SIZE} numbers ({', '.join(NAMES)}), got {action!r}") from None
    if a.shape != (SIZE,):
        raise ValueError(
            f"action of {agent}: expected shape ({SIZE},) ({', '.join(NAMES)}), got shape {a.shape}: {action!r}"
        )
    bad = ~np.isfinite(a)
    if bad.any():
        which = ", ".join(f"{NAMES[i]}={a[i]}" for i in np.flatnonzero(bad))
        raise ValueError(f"action of {agent}: {which} is not a finite number")
    if strict and (np.abs(a) > 1.0).any():
        which = ", ".join(f"{NAMES[i]}={a[i]:g}" for i in np.flatnonzero(np.abs(a) > 1.0))
        raise ValueError(f"action of {agent}: {which} outside [-1, 1]")
    return np.clip(a, -1.0, 1.0)


def check_discrete(agent: str, action) -> int:
    """``action`` as an index of `DISCRETE`; ValueError (naming ``agent``) for anything else."""
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
        raise ValueError(f"action of {agent}: expected an integer in [0, {len(DISCRETE)}), got {action!r}") from None
    if not 0 <= index < len(DISCRETE):
        raise ValueError(f"action of {agent}: {index} is not in [0, {len(DISCRETE)})")
    return index
