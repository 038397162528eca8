"""Dropped ball (MSL RC-8.6): every robot stays ``dropped_ball_distance`` (1 m) from the ball until START
(measured to the nearest point of its footprint, as every set-piece distance); a robot in its own penalty
area is exempt. START puts the ball in play at once, so this is judged when START is given."""

from __future__ import annotations

from .positions import PositionRule


class DroppedBallDistanceRule(PositionRule):
    name = "dropped_ball_distance"
    kinds = frozenset({"dropped_ball"})

    def offenders(self):
        m, p = self.m, self.p
        obs = m.obs
        d = self.clearances(self.spot_distances())
        out = []
        for i in range(obs.n):
            if d[i] < p.dropped_ball_distance and obs.active[i] and obs.penalty_area[i] != obs.own_side[i]:
                out.append(
                    (
                        i,
                        d[i],
                        p.dropped_ball_distance,
                        f"{obs.names[i]} is {d[i]:.3f} m from the dropped ball (the nearest point of its "
                        f"footprint; at least {p.dropped_ball_distance:.2f} m)",
                    )
                )
        return out
