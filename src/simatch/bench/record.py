"""Recording cost (issue 6): how much ``--record`` adds to a run's time, and how large a recorded minute is.

Two runs of the same scene and seed, without and with a recorder, on one core; the figure is the ratio of
their wall times (recorder finalisation included) and the file size per simulated minute. Both runs must
end with the same state digest (recording never changes a run), which the benchmark reports too.

Scenes, until the default strategy and the referee land:

* ``startpose``: ``msl_5v5`` with both coaches started; the robots drive back to their start poses after
  being placed elsewhere and then mostly stand: the cheapest full stack (perception, strategies, team
  fusion, coaches) and the most compressible data.
* ``scripted``: ``msl_5v5`` with `Chaser` robots: the nearest robot of each team chases the ball, takes it
  and kicks it upfield, the goalkeeper follows the ball along its goal line, the others shadow the ball from
  their formation places. Everything moves all the time, so the file size is that of a lively match.

The time of a run is the CPU time of this process (all its threads: the MCAP writer's too), which the
other jobs of a shared machine disturb far less than wall time; each pair is measured three times,
alternating, and the fastest run of each kind counts. Wall-time figures are reported beside them.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path

from ..strategy.base import Command, RobotStrategy

SCENES = {
    "startpose": {},
    "scripted": {"teams.cyan.strategy": "simatch.bench.record:Chaser",
                 "teams.magenta.strategy": "simatch.bench.record:Chaser"},
}
MOVED = {"cyan/2": (1.0, 4.0), "cyan/4": (-8.0, -5.0), "magenta/3": (-1.0, -4.0), "magenta/5": (8.0, 5.0)}


class Chaser(RobotStrategy):
    """A lively, simple player for benchmarks (not a team strategy: no passes, no roles, no rules)."""

    def decide(self, world) -> Command:
        ball = world.ball
        if ball is None or world.match_mode == 0:
            return Command()
        me = world.me
        if self.ctx.is_goalkeeper:
            gx = -self.ctx.field.half_length + 0.6
            return Command(target=(gx, max(-1.0, min(1.0, ball.y))), target_ori=0.0, max_vel=2.5)
        nearest = min([me] + world.teammates, key=lambda r: math.hypot(ball.x - r.x, ball.y - r.y)
                      if r.id != self.ctx.goalkeeper else math.inf)
        if nearest.id == me.id:
            if me.holding_ball:
                goal = (self.ctx.field.half_length, 2.0 * self.ctx.rng.uniform(-1, 1))
                ori = math.atan2(goal[1] - me.y, goal[0] - me.x)
                aligned = abs(math.remainder(ori - me.yaw, 2 * math.pi)) < 0.3
                return Command(target=(me.x, me.y), target_ori=ori, dribble=True, max_w=4.0,
                               kick_speed=7.0 if aligned else 0.0, lob=self.ctx.rng.uniform() < 0.2)
            return Command(target=(ball.x, ball.y), target_ori=math.atan2(ball.y - me.y, ball.x - me.x),
                           dribble=True, max_vel=3.0)
        sx, sy, _ = self.ctx.start
        tx = max(-self.ctx.field.half_length + 1.0, min(self.ctx.field.half_length - 1.0, 0.5 * sx + 0.6 * ball.x))
        ty = 0.6 * sy + 0.4 * ball.y
        return Command(target=(tx, ty), target_ori=math.atan2(ball.y - ty, ball.x - tx), max_vel=2.0)


def _one(overrides: dict, seconds: float, seed: int, path: Path | None) -> tuple[float, float, str, int]:
    """CPU and wall seconds (finalisation included), final digest, file size."""
    from ..record.recorder import Recorder
    from ..simulation import Simulation

    with Simulation("msl_5v5", seed=seed, overrides=overrides) as sim:
        recorder = Recorder.for_run(sim, path, command_line=["simatch", "bench"]) if path else None
        for name, (x, y) in MOVED.items():
            sim.set_model_state(name, x=x, y=y)
        for coach in sim.coaches.values():
            coach.start_play()
        c0, t0 = time.process_time(), time.perf_counter()
        sim.run(seconds=seconds)
        if recorder is not None:
            recorder.close()
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
        return cpu, wall, sim.state_digest(), (path.stat().st_size if path else 0)


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    out: dict = {}
    with tempfile.TemporaryDirectory(prefix="simatch-bench-record-") as tmp:
        _one(SCENES["scripted"], 2.0, 9, Path(tmp) / "warm.mcap")      # warm-up: kernels, imports, encoders
        for label, overrides in SCENES.items():
            plain, recorded, size, digests = [], [], 0, set()
            for rep in range(3):
                cpu, wall, digest, _ = _one(overrides, seconds, 1, None)
                plain.append((cpu, wall))
                digests.add(digest)
                path = Path(tmp) / f"{label}{rep}.mcap"
                cpu, wall, digest, size = _one(overrides, seconds, 1, path)
                recorded.append((cpu, wall))
                digests.add(digest)
                os.remove(path)
            (base, base_wall), (rec, rec_wall) = min(plain), min(recorded)
            out[f"record_{label}_rtf_plain"] = round(seconds / base, 1)
            out[f"record_{label}_rtf_recorded"] = round(seconds / rec, 1)
            out[f"record_{label}_overhead_pct"] = round(100.0 * (rec / base - 1.0), 1)
            out[f"record_{label}_ms_per_sim_s"] = round(1000.0 * (rec - base) / seconds, 2)
            out[f"record_{label}_wall_overhead_pct"] = round(100.0 * (min(w for _, w in recorded)
                                                                      / min(w for _, w in plain) - 1.0), 1)
            out[f"record_{label}_mb_per_sim_minute"] = round(size / 1e6 * 60.0 / seconds, 2)
            out[f"record_{label}_same_digest"] = len(digests) == 1
    return out
