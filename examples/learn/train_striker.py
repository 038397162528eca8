"""Train a striker with Stable-Baselines3 PPO on `striker_1v0` (CPU), then measure and show it.

    python examples/learn/train_striker.py --minutes 20           # the figures of docs/learning.md
    simatch run striker_1v0 --set teams.cyan.strategy=simatch.envs.policy:Policy \
        --set teams.cyan.strategy_params.file=striker_ppo/striker.zip

It trains for a wall-clock budget (``--minutes``), then plays ``--eval-episodes`` attempts on seeds never
trained on with the deterministic policy and counts the goals. It writes to ``--out``: the policy
(``striker.zip`` and ``striker.json``, for the `simatch.envs.policy:Policy` strategy), the learning curve
(``curve.png``, ``curve.csv``: every training episode with its step, wall time, return and end) and
``summary.json`` (the figures; printed too, as JSON with ``--json``).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np

#: evaluation seeds start here; training seeds are drawn below it
EVAL_SEED = 1_000_000_000
#: set by Ctrl-C or SIGTERM: the training ends at its next step, the policy is saved and evaluated as usual
STOP: list = []


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--minutes", type=float, default=20.0, help="training budget (default 20)")
    p.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="what the budget counts: wall-clock time (default), or this process's CPU time (on a shared machine: "
        "the time one core of a quiet machine would give)",
    )
    p.add_argument("--scene", default="striker_1v0", help="scene (default striker_1v0)")
    p.add_argument("--envs", type=int, default=8, help="environments stepped together (default 8)")
    p.add_argument("--subproc", action="store_true", help="step them in subprocesses (SubprocVecEnv)")
    p.add_argument("--seed", type=int, default=0, help="seed of the training (default 0)")
    p.add_argument("--eval-episodes", type=int, default=100, help="attempts played after training (default 100)")
    p.add_argument("--out", default="striker_ppo", help="output folder (default ./striker_ppo)")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    return p.parse_args(argv)


#: the action's velocity scale: within the omni4 model's limits (7.1 m/s, 24.6 rad/s), at the speeds a striker
#: can still take the ball with its dribbler (which takes a ball arriving at up to 3.5 m/s)
MAX_VEL, MAX_W = 3.5, 6.0


def make_env(scene: str):
    def thunk():
        import simatch.envs

        return simatch.envs.SimatchEnv(scene, max_vel=MAX_VEL, max_w=MAX_W)

    return thunk


class Curve:
    """SB3 callback: records every finished episode and stops training when the budget is spent."""

    def __new__(cls, *args, **kwargs):  # SB3 is imported only when training starts
        from stable_baselines3.common.callbacks import BaseCallback

        class _Curve(BaseCallback):
            def __init__(self, seconds: float, clock, progress, out: Path):
                super().__init__()
                self.seconds, self.clock, self.progress, self.out = seconds, clock, progress, out
                self.rows: list[dict] = []

            def _on_training_start(self) -> None:
                self.t0 = time.perf_counter()
                self.c0 = self.clock()

            def _on_step(self) -> bool:
                for i, done in enumerate(self.locals["dones"]):
                    if done:
                        info = self.locals["infos"][i]
                        self.rows.append(
                            {
                                "step": self.num_timesteps,
                                "wall_s": round(time.perf_counter() - self.t0, 2),
                                "cpu_s": round(time.process_time(), 2),
                                "return": round(float(info["episode"]["r"]), 3),  # VecMonitor's, unscaled
                                "end": info.get("end", ""),
                                "goal": int(info.get("end") == "goal"),
                            }
                        )
                        if len(self.rows) % 100 == 0:
                            write_curve(self.rows, self.out)
                if STOP:
                    return False  # Ctrl-C or SIGTERM: end the training here, then save and evaluate
                elapsed = self.clock() - self.c0
                if self.progress is not None:
                    self.progress.n = min(int(elapsed), self.progress.total)
                    recent = self.rows[-100:]
                    if recent:
                        self.progress.set_postfix(
                            steps=self.num_timesteps, goals=f"{np.mean([r['goal'] for r in recent]):.0%}"
                        )
                    self.progress.refresh()
                return elapsed < self.seconds

        return _Curve(*args, **kwargs)


def write_curve(rows: list[dict], out: Path) -> None:
    with open(out / "curve.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=["step", "wall_s", "cpu_s", "return", "end", "goal"])
        w.writeheader()
        w.writerows(rows)


def evaluate(model, normalize, scene: str, episodes: int) -> dict:
    """The deterministic policy on seeds never trained on, observations scaled as in training."""
    env = make_env(scene)()
    goals, returns, lengths = 0, [], []
    try:
        for k in range(episodes):
            obs, _ = env.reset(seed=EVAL_SEED + k)
            total, steps, done = 0.0, 0, False
            while not done:
                action, _ = model.predict(normalize.normalize_obs(obs), deterministic=True)
                obs, r, terminated, truncated, info = env.step(action)
                total, steps, done = total + r, steps + 1, terminated or truncated
            goals += info.get("end") == "goal"
            returns.append(total)
            lengths.append(steps * env.run.period)
    finally:
        env.close()
    return {
        "eval_episodes": episodes,
        "eval_goals": int(goals),
        "eval_goal_rate": goals / episodes if episodes else None,
        "eval_mean_return": round(float(np.mean(returns)), 3) if returns else None,
        "eval_mean_attempt_s": round(float(np.mean(lengths)), 3) if lengths else None,
    }


def plot(rows: list[dict], file: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    steps = np.array([r["step"] for r in rows])
    goal = np.array([r["goal"] for r in rows], dtype=float)
    ret = np.array([r["return"] for r in rows], dtype=float)
    window = max(1, min(200, len(rows) // 10 or 1))
    kernel = np.ones(window) / window
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    if len(rows) >= window:
        ax.plot(steps[window - 1 :], np.convolve(goal, kernel, "valid") * 100, color="tab:green", label="goals (%)")
    ax.set_xlabel("environment steps (one step = one 25 ms control period)")
    ax.set_ylabel(f"goals per episode, last {window} episodes [%]", color="tab:green")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    if len(rows) >= window:
        ax2.plot(steps[window - 1 :], np.convolve(ret, kernel, "valid"), color="tab:blue", alpha=0.7)
    ax2.set_ylabel("mean return", color="tab:blue")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(file)
    plt.close(fig)


def main(argv=None) -> int:
    args = parse_args(argv)
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor, VecNormalize
    from tqdm import tqdm

    from simatch.envs.policy import save_policy

    torch.set_num_threads(1)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    factory = SubprocVecEnv if args.subproc else DummyVecEnv
    monitor = VecMonitor(factory([make_env(args.scene) for _ in range(args.envs)]))
    monitor.seed(args.seed)
    # observations scaled by their running mean and deviation (kept with the policy), returns by theirs
    venv = VecNormalize(monitor, norm_obs=True, norm_reward=True, gamma=0.99)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=256,
        batch_size=256,
        n_epochs=10,
        learning_rate=3e-4,
        gamma=0.99,
        gae_lambda=0.95,
        ent_coef=0.0,
        policy_kwargs={"net_arch": [128, 128], "log_std_init": -0.5},
        seed=args.seed,
        device="cpu",
        verbose=0,
    )
    seconds = args.minutes * 60.0
    bar = tqdm(total=int(seconds), unit="s", desc="training", disable=not sys.stderr.isatty() or args.json)

    def stop(signum, frame):
        if STOP:
            raise KeyboardInterrupt
        STOP.append(signum)  # a second signal stops at once

    signal.signal(signal.SIGINT, stop)
    signal.signal(signal.SIGTERM, stop)
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    curve = Curve(seconds, clock, bar, out)
    t0, c0 = time.perf_counter(), time.process_time()
    model.learn(total_timesteps=10**10, callback=curve)
    train_s, train_cpu = time.perf_counter() - t0, time.process_time() - c0
    bar.close()
    venv.close()
    policy = save_policy(model, out / "striker.zip", make_env(args.scene)(), normalize=venv)
    rows = curve.rows
    write_curve(rows, out)
    last = rows[-200:]
    summary = {
        "scene": args.scene,
        "minutes": args.minutes,
        "clock": args.clock,
        "stopped_early": bool(STOP),
        "train_seconds": round(train_s, 1),
        "train_cpu_seconds": round(train_cpu, 1),
        "load_average": [round(v, 2) for v in os.getloadavg()],
        "train_steps": int(model.num_timesteps),
        "steps_per_second": round(model.num_timesteps / train_s, 1) if train_s > 0 else None,
        "train_episodes": len(rows),
        "train_goal_rate_last_200": round(float(np.mean([r["goal"] for r in last])), 3) if last else None,
        "policy": str(policy),
    }
    summary.update(evaluate(model, venv, args.scene, args.eval_episodes))
    spent = f"{train_cpu / 60:.1f} CPU min" if args.clock == "cpu" else f"{train_s / 60:.1f} min"
    plot(rows, out / "curve.png", f"PPO on {args.scene}: {summary['train_steps']:,} steps in {spent}")
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    if args.json:
        print(json.dumps(summary))
    else:
        for k, v in summary.items():
            print(f"{k:28s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
