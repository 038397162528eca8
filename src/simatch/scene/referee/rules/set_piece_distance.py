"""Distances at set pieces (MSL RC-8.3, RC-13, RC-15, RC-16): until the ball is in play, opponents stay
``opponent_distance`` (3 m) and the kicker's team-mates ``teammate_distance`` (2 m) from the ball. The rules
draw these as circles round the ball that robots must stay completely outside of, so the distance is
measured from the restart spot to the nearest point of the robot's footprint (its centre's distance less
its radius: with the shipped 0.25 m robots, an opponent's centre stays 3.25 m away). An opponent in its
own penalty area is exempt (the goalkeeper and the one defender allowed there). At a penalty kick every
robot but the kicker and the defending goalkeeper stays 3 m from the ball and outside the penalty area.
The kick-off is no exception (RC-8.3: the defending team keeps 3 m, as at every restart).
"""

from __future__ import annotations

from .positions import PositionRule


class SetPieceDistanceRule(PositionRule):
    name = "set_piece_distance"
    cautions = True
    kinds = frozenset({"kickoff", "free_kick", "throw_in", "goal_kick", "corner_kick", "penalty"})

    def offenders(self):
        m, p = self.m, self.p
        obs, r = m.obs, m.game.restart
        centre = self.spot_distances()
        kicker = self.designated_kicker(centre)
        d = self.clearances(centre)
        taker = m.touches.taker if m.touches.armed else -1
        k = obs.teams.index(r.team)
        penalty = r.kind == "penalty"
        box = obs.own_goal_side(obs.other(r.team))  # the penalty area of the defended goal
        out = []
        for i in range(obs.n):
            if not obs.active[i] or i == kicker or i == taker:
                continue
            mine = obs.team_ix[i] == k
            name = obs.names[i]
            if penalty:
                if not mine and obs.is_goalkeeper[i]:
                    continue
                if d[i] < p.opponent_distance:
                    out.append(
                        (
                            i,
                            d[i],
                            p.opponent_distance,
                            f"{name} is {d[i]:.3f} m from the penalty mark (the nearest point of its footprint; "
                            f"at least {p.opponent_distance:.2f} m)",
                        )
                    )
                elif obs.penalty_area[i] == box:
                    out.append((i, 0.0, 0.0, f"{name} is in the penalty area during the penalty kick"))
                continue
            if mine:
                limit, who = p.teammate_distance, "team-mate of the kicker"
            else:
                if obs.penalty_area[i] == obs.own_side[i]:
                    continue
                limit, who = p.opponent_distance, "opponent"
            if d[i] < limit:
                out.append(
                    (
                        i,
                        d[i],
                        limit,
                        f"{name} ({who}) is {d[i]:.3f} m from the ball (the nearest point of its footprint; "
                        f"at least {limit:.2f} m)",
                    )
                )
        return out
