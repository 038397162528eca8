"""The referee going from one stage of the match to the next (the stages are defined in `state.py`): a
half's clock runs out, the teams change ends, the next half kicks off or the penalty shoot-out begins, the
match ends with its winner. Each step is logged as it happens (``stage``, ``ends_changed``, ``match_end``).
"""

from __future__ import annotations

import math

from ...msgs.game_commands import MatchMode
from . import report
from .shootout import ShootOut
from .state import Phase


class StageChanges:
    """Mixed into `MslReferee`: what happens when a stage's time is up."""

    def _end_stage(self, now: float) -> None:
        """The current stage's clock ran out: the next stage begins (a shoot-out only when the score is level)."""
        m = self.m
        g = m.game
        ended = g.stage
        self._log(now, "stage", value=g.clock, limit=ended.duration or 0.0, detail=f"{ended.name} is over")
        nxt = g.next_stage()
        if nxt.kind == "shootout" and g.score[self.teams[0]] != g.score[self.teams[1]]:
            nxt = g.next_stage()
        if nxt.kind == "ended":
            self._end_match(now)
            return
        change = ended.kind == "half" and self.match_spec.change_ends
        if change:
            self._change_ends(now, "before the penalty shoot-out" if nxt.kind == "shootout" else "at half time")
        self._log(now, "stage", value=nxt.duration or 0.0, detail=f"{nxt.name} begins")
        if nxt.kind == "shootout":
            self.shootout = ShootOut(m.obs, self.p, m.spots, self.match_spec.kickoff)
            restart = self.shootout.next_restart()
            reason = "penalty shoot-out"
        else:
            half = next((s.half for s in g.stages[g.stage_index :] if s.kind == "half"), 1)
            first = self.match_spec.kickoff
            g.kickoff_team = first if half % 2 == 1 else m.obs.other(first)
            restart = m.spots.kickoff(g.kickoff_team)
            reason = "half time" if nxt.kind == "break" else f"{nxt.name}"
        self._stop(now, restart, reason)
        if change:  # at once, whatever the step: the perception turns from the next observation on
            self._publish(now, force=True)

    def _change_ends(self, now: float, when: str) -> None:
        """The teams change ends: every team's frame turns (the simulator's perception, the commands' points,
        every side the rules judge), the robots are placed at their start poses for the new ends (sent-off
        robots parked beside their new half) and the ball on the centre mark."""
        m = self.m
        obs = m.obs
        for t in self.teams:
            sign = -obs.sign[t]
            obs.set_sign(t, sign)
            self.world.set_team_sign(t, sign)
        spec = self.scene.spec
        for t in self.teams:
            mirrored = obs.sign[t] != obs.scene_sign[t]
            for rid, (x, y, yaw) in zip(spec.teams[t].robot_ids(), spec.teams[t].start):
                i = obs.index[f"{t}/{rid}"]
                if i in self.discipline.off_until:
                    self.discipline.park(i)
                    continue
                if mirrored:
                    x, y, yaw = -x, -y, math.remainder(yaw + math.pi, 2.0 * math.pi)
                self.world.set_model_state(obs.names[i], x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)
        self._place_ball(0.0, 0.0)
        m.touches.on_restart()
        for rule in self.rules:
            rule.on_restart()
        m.game.version += 1
        sides = ", ".join(f"{t} attacks {obs.attacks(t)}" for t in self.teams)
        self._log(
            now,
            "ends_changed",
            detail=f"the teams change ends {when}: {sides}; every robot is placed at its start pose for these "
            f"ends, the ball on the centre mark",
        )

    def _end_match(self, now: float) -> None:
        """The match is over: STOP to every team, the final score and the winner in the log."""
        g = self.m.game
        winner = report.winner(self)
        score = ", ".join(f"{t} {g.score[t]}" for t in self.teams)
        extra = ""
        if self.shootout is not None:
            extra = " (shoot-out " + ", ".join(f"{t} {self.shootout.goals(t)}" for t in self.teams) + ")"
        self._send(now, MatchMode.STOPROBOT, "", "the match is over")
        g.stage_index = len(g.stages) - 1
        g.go(Phase.ENDED)
        g.version += 1
        self._log(
            now,
            "match_end",
            team=winner or "",
            detail=f"final score {score}{extra}: " + (f"{winner} wins" if winner else "a draw"),
        )
        self.done = True
        self._publish(now, force=True)
