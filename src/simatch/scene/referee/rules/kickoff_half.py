"""Kick-off positions (MSL RC-8.3): until the ball is in play every robot stays in its own half (its
centre on its side of the half-way line or on it). The kicker, touching the ball on the line, is exempt once
it has touched it."""

from __future__ import annotations

from .positions import PositionRule


class KickoffHalfRule(PositionRule):
    name = "kickoff_half"
    kinds = frozenset({"kickoff"})

    def offenders(self):
        m = self.m
        obs = m.obs
        taker = m.touches.taker if m.touches.armed else -1
        out = []
        for i in range(obs.n):
            over = obs.attack_sign[i] * obs.X[i]
            if over > 0.0 and obs.active[i] and i != taker:
                out.append((i, over, 0.0, f"{obs.names[i]} is {over:.3f} m inside the opponent half at the kick-off"))
        return out
