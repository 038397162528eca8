"""The Gazebo-like interface over the bus, for privileged clients: set_model_state, set_link_state and
apply_wrench requests (ModelState, LinkState, ApplyWrench messages on the topics of the same names).

Fair play decides who may call them (only the organiser's ``admin`` credential: see `fairplay`); this node
applies what reaches it, at the server's next control tick, and turns a request the simulator refuses (an
unknown model, a non-finite value) into a ``bad_request`` event instead of an error.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics

log = logging.getLogger(__name__)

_POSE = ("x", "y", "z")
_QUAT = ("qw", "qx", "qy", "qz")
_TWIST = ("vx", "vy", "vz", "wx", "wy", "wz")


def state_of(msg: Any) -> dict[str, float]:
    """The keyword arguments of set_model_state for a ModelState/LinkState request: every field, except an
    all-zero quaternion (not given: keep the orientation)."""
    state = {k: float(getattr(msg, k)) for k in _POSE + _TWIST}
    quat = {k: float(getattr(msg, k)) for k in _QUAT}
    if any(quat.values()):
        state.update(quat)
    return state


class WorldService(Node):
    phase = Phase.JUDGE
    name = "world_service"

    def __init__(self, world: Any, emit: Callable[..., None]):
        """``world`` has set_model_state, set_link_state and apply_wrench (a Simulation);
        ``emit(type, detail=...)`` logs an event."""
        self.world = world
        self.emit = emit
        self.applied = 0

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus = ctx.bus
        self.subs = [
            bus.subscribe(topics.SET_MODEL_STATE, msgs.ModelState, self._model_state),
            bus.subscribe(topics.SET_LINK_STATE, msgs.LinkState, self._link_state),
            bus.subscribe(topics.APPLY_WRENCH, msgs.ApplyWrench, self._wrench),
        ]

    def _apply(self, what: str, call: Callable[[], None]) -> None:
        try:
            call()
        except ValueError as exc:  # CommandError: unknown model, bad value
            log.warning("%s refused: %s", what, exc)
            self.emit("bad_request", detail=f"{what}: {exc}")
            return
        self.applied += 1

    def _model_state(self, msg) -> None:
        self._apply(f"set_model_state({msg.name!r})", lambda: self.world.set_model_state(msg.name, **state_of(msg)))

    def _link_state(self, msg) -> None:
        self._apply(f"set_link_state({msg.name!r})", lambda: self.world.set_link_state(msg.name, **state_of(msg)))

    def _wrench(self, msg) -> None:
        self._apply(
            f"apply_wrench({msg.name!r})",
            lambda: self.world.apply_wrench(
                msg.name, force=(msg.fx, msg.fy, msg.fz), torque=(msg.tx, msg.ty, msg.tz), duration=msg.duration
            ),
        )

    def stop(self) -> None:
        for sub in getattr(self, "subs", []):
            sub.close()
