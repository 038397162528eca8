"""Recording cost (issue 6): how much ``--record`` adds to a run's time, and how large a recorded minute is.

Two runs of the same scene and seed, without and with a recorder; the figures are the ratios of their times
(recorder finalisation included), the file size per simulated minute and where those bytes go (per topic).
Both runs must end with the same state digest (recording never changes a run), which is reported too.

Scenes:

* ``match``: ``msl_5v5`` as shipped (both teams' default strategy, the automatic referee), from the
  kick-off: the run the issue's targets are about.
* ``scripted``: ``msl_5v5`` with `Chaser` robots and the coaches giving the commands (no referee): the
  nearest robot of each team chases the ball, takes it and kicks it upfield, the goalkeeper follows the
  ball along its goal line, the others shadow the ball from their formation places. Everything moves all
  the time (the liveliest data, the largest file), and the strategies cost almost nothing, so the
  recording's own cost weighs most.

Times: the CPU time of the process and its writer process (the recorder's compression and file writes,
`simatch.record.writer`), which other jobs on a shared machine disturb far less than wall time, and the
CPU time of the simulation thread alone (``main``): with a free core that is what the run waits for. Each
pair is measured five times, alternating, and the fastest run of each kind counts (on a shared machine
three pairs left the figure moving by a third from one bench to the next); wall-time figures (the run
time a user waits) are reported beside them. Besides the ratios, the milliseconds of CPU time the recording
adds per simulated second (both processes, and the simulation thread alone) and what the plain run costs
per simulated second: the match itself may get faster, which raises the ratio for the same recording
cost.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import zstandard

from ..strategy.base import Command, RobotStrategy

SCENES = {
    "match": {},
    "scripted": {
        "teams.cyan.strategy": "simatch.bench.record:Chaser",
        "teams.magenta.strategy": "simatch.bench.record:Chaser",
        "judge.kind": "none",
    },
}
PAIRS = 5  # alternating runs without and with a recorder, per scene
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
        nearest = min(
            [me] + world.teammates,
            key=lambda r: math.hypot(ball.x - r.x, ball.y - r.y) if r.id != self.ctx.goalkeeper else math.inf,
        )
        if nearest.id == me.id:
            if me.holding_ball:
                goal = (self.ctx.field.half_length, 2.0 * self.ctx.rng.uniform(-1, 1))
                ori = math.atan2(goal[1] - me.y, goal[0] - me.x)
                aligned = abs(math.remainder(ori - me.yaw, 2 * math.pi)) < 0.3
                return Command(
                    target=(me.x, me.y),
                    target_ori=ori,
                    dribble=True,
                    max_w=4.0,
                    kick_speed=7.0 if aligned else 0.0,
                    lob=self.ctx.rng.uniform() < 0.2,
                )
            return Command(
                target=(ball.x, ball.y), target_ori=math.atan2(ball.y - me.y, ball.x - me.x), dribble=True, max_vel=3.0
            )
        sx, sy, _ = self.ctx.start
        tx = max(-self.ctx.field.half_length + 1.0, min(self.ctx.field.half_length - 1.0, 0.5 * sx + 0.6 * ball.x))
        ty = 0.6 * sy + 0.4 * ball.y
        return Command(target=(tx, ty), target_ori=math.atan2(ball.y - ty, ball.x - tx), max_vel=2.0)


def _one(label: str, seconds: float, seed: int, path: Path | None) -> tuple[float, float, float, str, int]:
    """CPU seconds of the process and of this thread, wall seconds (finalisation included), final digest,
    file size."""
    from ..record.recorder import Recorder
    from ..simulation import Simulation

    with Simulation("msl_5v5", seed=seed, overrides=SCENES[label]) as sim:
        recorder = Recorder.for_run(sim, path, command_line=["simatch", "bench"]) if path else None
        if label == "scripted":
            for name, (x, y) in MOVED.items():
                sim.set_model_state(name, x=x, y=y)
            for coach in sim.coaches.values():
                coach.start_play()
        c0, k0, m0, t0 = time.process_time(), _children(), time.thread_time(), time.perf_counter()
        sim.run(seconds=seconds, until_done=False)
        if recorder is not None:
            recorder.close()  # waits for the writer process: its CPU time is counted below
        cpu = time.process_time() - c0 + _children() - k0
        main, wall = time.thread_time() - m0, time.perf_counter() - t0
        return cpu, main, wall, sim.state_digest(), (path.stat().st_size if path else 0)


def _children() -> float:
    """CPU seconds of the ended child processes (the recorder's writer process)."""
    t = os.times()
    return t.children_user + t.children_system


def topic_sizes(path: Path, seconds: float) -> dict[str, float]:
    """MB per simulated minute of each kind of topic (robot and team topics grouped by their last part),
    each compressed alone, chunk by chunk, as the recorder compresses: where the bytes of a recording go."""
    from ..record import Recording
    from ..record.layout import CHUNK_NS
    from ..record.recorder import COMPRESSION_LEVEL

    compressor = zstandard.ZstdCompressor(level=COMPRESSION_LEVEL)
    sizes: dict[str, int] = defaultdict(int)
    pending: dict[str, list[bytes]] = defaultdict(list)
    chunk = 0

    def flush() -> None:
        for kind, items in pending.items():
            sizes[kind] += len(compressor.compress(b"".join(items)))
        pending.clear()

    for topic, t, data in Recording(path).raw():
        if t // CHUNK_NS != chunk:
            flush()
            chunk = t // CHUNK_NS
        pending["scene" if topic.startswith("scene/") else topic.rsplit("/", 1)[-1]].append(bytes(data))
    flush()
    per_minute = 60.0 / seconds / 1e6
    return {kind: round(n * per_minute, 3) for kind, n in sorted(sizes.items(), key=lambda kv: -kv[1])}


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    out: dict = {}
    with tempfile.TemporaryDirectory(prefix="simatch-bench-record-") as tmp:
        _one("scripted", 2.0, 9, Path(tmp) / "warm.mcap")  # warm-up: kernels, imports, encoders
        for label in SCENES:
            plain, recorded, size, digests = [], [], 0, set()
            for rep in range(PAIRS):
                cpu, main, wall, digest, _ = _one(label, seconds, 1, None)
                plain.append((cpu, main, wall))
                digests.add(digest)
                path = Path(tmp) / f"{label}{rep}.mcap"
                cpu, main, wall, digest, size = _one(label, seconds, 1, path)
                recorded.append((cpu, main, wall))
                digests.add(digest)
                if rep == 0:
                    out[f"record_{label}_topics_mb_per_sim_minute"] = topic_sizes(path, seconds)
                os.remove(path)
            base, rec = [min(r[i] for r in plain) for i in range(3)], [min(r[i] for r in recorded) for i in range(3)]
            out[f"record_{label}_rtf_plain"] = round(seconds / base[0], 1)
            out[f"record_{label}_rtf_recorded"] = round(seconds / rec[0], 1)
            out[f"record_{label}_overhead_pct"] = round(100.0 * (rec[0] / base[0] - 1.0), 1)
            out[f"record_{label}_main_overhead_pct"] = round(100.0 * (rec[1] / base[1] - 1.0), 1)
            out[f"record_{label}_wall_overhead_pct"] = round(100.0 * (rec[2] / base[2] - 1.0), 1)
            out[f"record_{label}_ms_per_sim_s"] = round(1000.0 * (rec[0] - base[0]) / seconds, 2)
            out[f"record_{label}_main_ms_per_sim_s"] = round(1000.0 * (rec[1] - base[1]) / seconds, 2)
            out[f"record_{label}_plain_ms_per_sim_s"] = round(1000.0 * base[0] / seconds, 2)
            out[f"record_{label}_mb_per_sim_minute"] = round(size / 1e6 * 60.0 / seconds, 2)
            out[f"record_{label}_same_digest"] = len(digests) == 1
    return out
