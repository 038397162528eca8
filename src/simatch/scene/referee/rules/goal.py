"""Goals, and whether they count (MSL RC-10.1, RC-8.4, RC-15).

A goal is scored when the whole ball has passed over the whole goal line (past the painted line's outer
edge: the line belongs to the field) between the posts and under the crossbar (judged at the physics rate,
the first step the ball is wholly over the line). It counts unless:

* it came directly from a kick-off, free kick, throw-in, goal kick or corner kick: no robot but the taker
  touched the ball since the restart. "Directly" is meant as the Laws of the Game mean it for an indirect
  kick: the ball must touch another player, of either team, before it enters the goal; so a defender who
  plays the ball into its own goal after the opponents' kick-off scores for them, and the taker scores
  validly after an opponent played the ball;
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
        f = obs.field
        depth = side * x - f.half_length  # the ball's centre past the goal line's centre
        limit = 0.5 * f.line_width + obs.ball_radius  # wholly past the line's outer edge
        why = self.invalid(scoring)
        touches = self.m.touches
        last = touches.last
        shooter = last if last >= 0 and obs.team_of[last] == scoring else -1
        if why is None:
            own = last >= 0 and obs.team_of[last] == defending
            who = f" by {obs.names[last]}" if last >= 0 else ""
            return Call(
                "goal",
                team=scoring,
                # the event's team is the one the goal counts for; its robot is the scorer when it is of that
                # team (an own goal's scorer, of the other team, is named in the detail and in the result)
                robot=-1 if own else last,
                scorer=last,
                x=x,
                y=y,
                value=depth,
                limit=limit,
                detail=f"goal for {scoring}{': own goal' if own else ''}{who}: the ball's centre is {depth:.3f} m "
                f"past the middle of {defending}'s goal line, the whole ball past the line (limit {limit:.4f} m: "
                f"half the line's width and the ball's radius), between the posts, under the bar",
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
        since = touches.since_restart
        restart = m.game.restart
        if restart is not None and restart.kind in NO_DIRECT_GOAL and restart.team and len(since) < 2:
            # "directly": no robot but the one that took the set piece touched the ball (a robot of either
            # team touching it makes the goal count, an own goal included)
            what = NAMES[restart.kind]
            names = ", ".join(obs.names[i] for i in since) or "no robot"
            into = " into the kicking team's own goal" if scoring != restart.team else ""
            return (
                len(since),
                2,
                f"direct goal from a {what}{into}: since {restart.team}'s {what} only {names} touched the ball "
                f"(another robot, of either team, must touch it first)",
            )
        if restart is not None and restart.kind == "dropped_ball" and len(since) < 2:
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
