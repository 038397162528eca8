"""The Gymnasium spaces of an agent: observation (vector or `Dict`) and action (`Box` or `Discrete`)."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from . import action
from .observation import Layout

OBSERVATION_FORMS = ("vector", "dict")


def observation_space(layout: Layout, form: str) -> spaces.Space:
    box = spaces.Box(layout.low, layout.high, dtype=np.float32)
    if form == "vector":
        return box
    lows, highs = layout.split(layout.low), layout.split(layout.high)
    return spaces.Dict({name: spaces.Box(lows[name], highs[name], dtype=np.float32) for name in layout.parts})


def action_space(action_type: str, limits: action.Limits | None = None) -> spaces.Space:
    """The action space of an agent whose robot has ``limits`` (an aerial robot's has its climb as well)."""
    if action_type == "discrete":
        return spaces.Discrete(limits.moves if limits is not None else len(action.DISCRETE))
    return spaces.Box(-1.0, 1.0, shape=(limits.size if limits is not None else action.SIZE,), dtype=np.float32)


def check_form(form: str) -> str:
    if form not in OBSERVATION_FORMS:
        raise ValueError(f"observation form must be one of {', '.join(OBSERVATION_FORMS)}, got {form!r}")
    return form


def check_render(mode: str | None) -> None:
    """The environments draw nothing themselves: a run is watched in the web UI (``simatch run --view``) or
    recorded (``--record``) and replayed."""
    if mode is not None:
        raise ValueError(
            f"render_mode {mode!r}: simatch environments do not render; watch a run with simatch run --view, "
            f"or record it (--record) and open it with simatch serve"
        )
