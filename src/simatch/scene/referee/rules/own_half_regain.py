"""A goal after regaining the ball in the own half (MSL RC-10.1.2): a team that won the ball in its own half
scores validly only after a team-mate received it in the opponent half after it rolled freely at least
``regain_pass_roll`` (1 m). The MSL's answer to a team that takes the ball at its own goal and runs or
shoots it the length of the field: it must play a pass into the opponent half first.

"Won the ball" is read from the touch history (`touches.py`): a robot of the team touches the ball and the
previous touch since the restart was the other team's, or nobody's (a restart: the taker's first touch
wins the ball where the spot is, so a goal kick or a free kick in the own half counts, a kick-off on the
half-way line does not). In its own half means the ball's centre behind the half-way line; received in the
opponent half means the ball's centre past it when the team-mate touched it. A touch by the other team
ends the team's possession: winning the ball back is judged again where that happens.

Not a foul: a goal scored without that pass is disallowed as any other invalid goal (goal kick for the
defending team). `GoalRule` asks this rule whether a goal counts.
"""

from __future__ import annotations

from ..state import LIVE
from .base import Rule


class OwnHalfRegainRule(Rule):
    name = "own_half_regain"
    phases = LIVE

    def invalid(self, scoring: str) -> tuple[float, float, str] | None:
        """(value, limit, reason) if a goal for ``scoring`` does not count under RC-10.1.2, else None."""
        obs, touches = self.m.obs, self.m.touches
        k = obs.teams.index(scoring)
        if not touches.needs_pass(k):
            return None
        x, y = touches.won_at[k]
        won_by = touches.won_by[k]
        roll = touches.longest_roll[k]
        limit = self.p.regain_pass_roll
        longest = (
            f"the longest free roll before a team-mate's touch there was {roll:.2f} m"
            if roll > 0.0
            else "no team-mate touched it there after a pass"
        )
        return (
            roll,
            limit,
            f"{scoring} won the ball in its own half at ({x:.2f}, {y:.2f}) ({obs.names[won_by]}) "
            f"and no team-mate received it in {obs.other(scoring)}'s half after it rolled freely "
            f"{limit:.2f} m ({longest}) (RC-10.1.2)",
        )
