"""Load nubot's compiled kernels before they are needed.

Some kernels are first used only once open play begins (interceptions, receiving spots), seconds into a
match: loading a kernel from the on-disk cache (or, on a fresh clone, compiling it) then costs tens of
milliseconds at that moment. `load_kernels` calls each one once on a tiny example with the argument types
of a match, so that a benchmark can load them all before it starts its clock.
"""

from __future__ import annotations

import numpy as np

from ...compiled import bind
from ...field import FieldGeometry
from . import positions
from .active import _DIRECTIONS, dribble_choice
from .assignment import assign, assist_spots, open_slots
from .avoidance import no_charging, sub_target
from .ballpath import BallPath, intercepts, team_intercepts
from .evaluate import lane_clear, position_value, shot_window
from .positions import Areas, as_called, score_spots


class _Robot:
    """The attributes `assign` reads of a team-mate."""

    def __init__(self, rid: int, x: float, y: float):
        self.id, self.x, self.y, self.role, self.role_time = rid, x, y, -1, 1e9


def load_kernels() -> None:
    """Call every nubot kernel once (the results are thrown away)."""
    opps = np.array([(1.0, 0.5, 0.0, 0.0), (3.0, -1.0, 0.1, 0.0)])
    mates = np.array([(0.0, 0.0, 0.0, 0.0, 1.0, 0.0), (-2.0, 1.0, 0.0, 0.0, 2.0, 0.0)])
    sub_target(0.0, 0.0, 4.0, 0.0, opps, mates, 1, 2.0, 0.2, 0.45, 1.1, 0.3, 0)
    no_charging(0.0, 0.0, 0.5, 0.0, 1.0, 0.0, opps, 0.55, 0.5, 2.0)
    path = BallPath(0.5, 0.2, 0.11, 1.0, 0.3, 0.0, 0.4, 0.11, 12.0, 8.0)
    rows = np.array([(0.0, 0.0, 0.0, 0.0, 0.1), (1.0, 0.5, 0.0, 0.0, 0.0)]).T.copy()
    intercepts(path, rows[0], rows[1], rows[2], rows[3], 3.0, 2.5, rows[4])
    us = np.array([(0.0, 0.0, 0.0, 0.0, 1.0, 0.5), (-2.0, 1.0, 0.3, 0.0, 2.0, 1.0)])
    team_intercepts(path, us, opps, 0.5, 0.2, 0.2, 3.0, 2.5)
    cx, cy = np.linspace(-5.0, 5.0, 4), np.linspace(-3.0, 3.0, 4)
    for near in (None, (1.0, 1.0)):
        score_spots(cx, cy, 0.0, 0.0, np.array([1.0]), np.array([0.5]), 11.0, 3.0, 8.5, near)
    bind(assist_spots)(cx, cy, 0.0, 0.0, opps, 11.0, 3.0, 8.5, np.nan, np.nan, np.empty((2, 2)))
    # the ball player's judges, as it calls them (from Python, and inside the dribble's kernel)
    shot_window(8.0, 0.5, opps, 11.0, 1.2, 10.0, 0.22)
    lane_clear(0.0, 0.0, 4.0, 1.0, opps, 3.0, 0.0)
    position_value(3.0, 1.0, opps, 11.0)
    pitch = Areas(FieldGeometry(), 0.4).pitch
    bind(dribble_choice)(
        8.0, 0.5, 0.3, 1.0, 7.5, 0.0, 2.85, opps, pitch, False, True, 7.0, 1.2, 10.0, 1.0, 0.0, False, *_DIRECTIONS[0]
    )
    robots = [_Robot(2, 0.0, 0.0), _Robot(3, 1.0, 1.0)]
    slots = [(1, 2.0, 0.0, 0.0, 0.0), (2, -2.0, 1.0, 0.0, 0.0)]
    assign(robots, slots, 0.5)
    assign(robots, slots, 0.5, around=(0.0, 0.0, 1.0))
    # open play's slots, attacking (the receiving spots) and defending (the outlet point)
    table = np.array([(0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0, 1e9), (-2.0, 1.0, 0.0, 0.0, 2.0, 0.0, -1.0, 0.1)])
    rest = np.array([0, 1], dtype=np.int64)
    for attacking in (True, False):
        passive = as_called(positions.passive_point)(pitch, 0.5, 0.2, attacking)
        midfield = as_called(positions.midfield_point)(pitch, 0.5, 0.2, attacking, opps)
        spots = np.array([as_called(positions.outlet_point)(pitch, 0.5, 0.2)])
        bind(open_slots)(table, rest, attacking, spots, *passive, *midfield, 0.5, 0.2, pitch, 0.5, np.empty((2, 4)))
