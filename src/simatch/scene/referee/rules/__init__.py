"""The rules the referee judges, one per file (see `base.py` for what a rule is).

`CONTROL_RULES` run at the control period, in this order (the first call that stops play wins; the
others of the same period are still logged). Goals and the ball leaving the field are judged at the
physics rate by the referee itself, with `GoalRule` and `BallOutRule` deciding what a crossing means
(`GoalRule` asks `OwnHalfRegainRule` too).
"""

from __future__ import annotations

from .ball_holding import BallHoldingRule
from .ball_out import BallOutRule
from .ball_rotation import BallRotationRule
from .base import Call, Rule
from .charging import ChargingRule
from .double_touch import DoubleTouchRule
from .dribbling import DribblingRule
from .dropped_ball_distance import DroppedBallDistanceRule
from .goal import GoalRule
from .goal_area import GoalAreaRule
from .goalkeeper_contact import GoalkeeperContactRule
from .kickoff_half import KickoffHalfRule
from .lob import LobRule
from .no_progress import NoProgressRule
from .penalty_area import PenaltyAreaRule
from .positions import PositionRule
from .pushing import PushingRule
from .restart_timeout import RestartTimeoutRule
from .set_piece_distance import SetPieceDistanceRule

CONTROL_RULES: tuple[type[Rule], ...] = (
    DoubleTouchRule,
    SetPieceDistanceRule,
    KickoffHalfRule,
    DroppedBallDistanceRule,
    RestartTimeoutRule,
    ChargingRule,
    PushingRule,
    GoalkeeperContactRule,
    LobRule,
    BallHoldingRule,
    BallRotationRule,
    DribblingRule,
    GoalAreaRule,
    PenaltyAreaRule,
    NoProgressRule,
)

__all__ = ["BallOutRule", "CONTROL_RULES", "Call", "GoalRule", "PositionRule", "Rule"]
