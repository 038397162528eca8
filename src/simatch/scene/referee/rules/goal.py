"""Goals, and whether they count (MSL RC-10.1, RC-8.4, RC-15).

A goal is scored when the whole ball has passed over the goal line between the posts and under the
crossbar (judged at the physics rate, the first step the ball is wholly over the line). It counts unless:

* it came directly from a kick-off, free kick, throw-in, goal kick or corner kick: the kicking team needs two
  of its robots to have touched the ball since the restart (and a goal into the kicking team's own goal
  needs any robot besides the taker to have touched it);
* it came directly from a dropped ball: two robots (of any team) must have touched it;
* the shooter — the last robot to touch the ball, when it belongs to the scoring team — stood in its own
  half when it touched the ball (an own goal, last touched by the defending team, counts);
* no robot touched the ball since the restart;
* the scoring team won the ball in its own half and no team-mate received it in the opponent half after a
  free roll of 1 m (RC-10.1.2, `own_half_regain.py`).

A goal that counts restarts with a kick-off for the team that conceded; one that does not restarts with a
goal kick for the defending team.
"""

from __future__ import annotations

from ..restarts import NAMES
from ..state import LIVE
from .base import Call, Rule
from .own_half_regain import OwnHalfRegainRule

#: restarts from which no goal may be scored directly
NO_DIRECT_GOAL = frozenset({"kickoff", "free_kick", "throw_in", "goal_kick", "corner_kick"})


class GoalRule(Rule):
    name = "goal"
    phases = LIVE

    def __init__(self, match):
        super().__init__(match)
        self.regain = OwnHalfRegainRule(match) if "own_half_regain" not in self.p.disabled_rules else None

    def in_goal(self, y: float, z: float) -> bool:
        """A ball wholly over a goal line at lateral ``y`` and height ``z`` (centre) is in the goal."""
        f = self.m.obs.field
        return f.goals and abs(y) < 0.5 * f.goal_width and z < f.goal_height

    def crossed(self, side: int, x: float, y: float, z: float) -> Call:
        """The ball is wholly over the goal line at ``side`` (-1: cyan's), inside the goal."""
        obs = self.m.obs
        defending = obs.defender_of(side)
        scoring = obs.other(defending)
        depth = side * x - obs.field.half_length
        why = self.invalid(scoring)
        touches = self.m.touches
        last = touches.last
        shooter = last if last >= 0 and obs.team_of[last] == scoring else -1
        if why is None:
            who = f" by {obs.names[last]}" if last >= 0 else ""
            own = " (own goal)" if last >= 0 and obs.team_of[last] == defending else ""
            return Call(
                "goal",
                team=scoring,
                robot=last,
                x=x,
                y=y,
                value=depth,
                limit=obs.ball_radius,
                detail=f"goal for {scoring}{who}{own}: the whole ball is {depth:.2f} m over {defending}'s "
                f"goal line (ball radius {obs.ball_radius:.2f} m), between the posts, under the bar",
                restart=self.m.spots.kickoff(defending),
                goal_for=scoring,
            )
        value, limit, reason = why
        return Call(
            "goal_disallowed",
            team=scoring,
            robot=shooter if shooter >= 0 else last,
            x=x,
            y=y,
            value=value,
            limit=limit,
            detail=f"no goal for {scoring}: {reason}; goal kick for {defending}",
            restart=self.m.spots.goal_kick(defending, side, y),
        )

    def invalid(self, scoring: str) -> tuple[float, float, str] | None:
        """(value, limit, reason) if a goal for ``scoring`` does not count now, else None."""
        m = self.m
        obs, touches = m.obs, m.touches
        k = obs.teams.index(scoring)
        since = touches.since_restart
        restart = m.game.restart
        if restart is not None and restart.kind in NO_DIRECT_GOAL and restart.team:
            what = NAMES[restart.kind]
            if scoring == restart.team:
                mates = touches.touched_by(k)
                if len(mates) < 2:
                    names = ", ".join(obs.names[i] for i in mates) or "no robot"
                    return (
                        len(mates),
                        2,
                        f"direct goal from a {what}: since the {what} only {names} of "
                        f"{scoring} touched the ball (two robots of the kicking team must)",
                    )
            elif len(since) < 2:
                return (len(since), 2, f"direct goal from {restart.team}'s {what} into its own goal")
        elif restart is not None and restart.kind == "dropped_ball" and len(since) < 2:
            return (len(since), 2, "direct goal from a dropped ball (two robots must touch the ball first)")
        last = touches.last
        if last < 0 or not since:
            return (0, 1, "no robot touched the ball since the restart")
        if obs.team_of[last] == scoring:
            x = touches.touch_x[last]
            if not obs.in_opponent_half(last, x):
                return (
                    obs.attack_sign[last] * x,
                    0.0,
                    f"the shooter {obs.names[last]} kicked from its own half (x = {x:.2f} m)",
                )
        if self.regain is not None:
            return self.regain.invalid(scoring)
        return None
