"""simatch's learning environments beside their peers, in one run: env steps and simulated seconds per second.

    python scripts/compare_envs.py                 # creates the peers' venvs on first use (a few minutes)
    python scripts/compare_envs.py --seconds 120 --json

Every environment is stepped with uniformly random actions for the same number of simulated seconds, one
environment on one core (torch and BLAS limited to one thread), episodes reset as they end; CPU seconds of the
measuring process are counted beside the wall clock, since a shared machine's wall clock counts the others' work.

Peers, each in a venv of its own under ``--peers-dir`` (default ``.venv-peers/``), which this script creates:

* ``vmas`` football (VMAS 1.5, PyTorch on the CPU): 5 learning agents against 5 of its scripted AI, one env, and
  32 envs batched in one process (VMAS's vectorisation: env steps count every batched env);
* ``dm_control`` soccer (2 v 2 BOXHEAD walkers, MuJoCo).

Why separate venvs: dm_control needs the ``mujoco`` package at 3.x (it fails on 4.0), while simatch runs on
``mujoco-core`` 4 — both are the ``mujoco`` module, so they cannot share a venv. VMAS pulls the retired ``gym``
and ``pyglet<=1.5.27``, which have no place in simatch's venv either.

simatch's rows run in this interpreter (the project's venv, with the ``learn`` extra).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}

PEERS = {
    # name: (packages pip installs in its venv, the measuring program: prints one JSON object)
    "vmas": (
        ["torch==2.13.0", "vmas"],
        """
        import json, sys, time, torch
        torch.set_num_threads(1)
        import vmas
        seconds, num_envs = float(sys.argv[1]), int(sys.argv[2])
        env = vmas.make_env("football", num_envs=num_envs, device="cpu", continuous_actions=True, seed=0,
                            n_blue_agents=5, n_red_agents=5, ai_red_agents=True, max_steps=None)
        dt = float(env.world.dt)
        env.reset()
        steps = max(1, round(seconds / dt))
        cpu, wall = time.process_time(), time.perf_counter()
        for _ in range(steps):
            actions = [env.get_random_action(agent) for agent in env.agents]
            obs, rews, dones, info = env.step(actions)
            if dones.any():
                for i in torch.nonzero(dones).flatten().tolist():
                    env.reset_at(i)
        print(json.dumps({"steps": steps * num_envs, "sim_seconds": steps * dt * num_envs, "dt": dt,
                          "agents": len(env.agents), "cpu_s": time.process_time() - cpu,
                          "wall_s": time.perf_counter() - wall, "version": vmas.__version__}))
        """,
    ),
    "dm_control": (
        # dm_control 1.0.50 accepts mujoco>=3.17 but fails on 4.0 (MjModel.flex_vertedge is gone): 3.17 it is;
        # its soccer pitch texture needs PIL, which it does not declare
        ["dm_control", "mujoco==3.17.0", "pillow"],
        """
        import json, sys, time
        import numpy as np
        from dm_control.locomotion import soccer as dm_soccer
        import dm_control
        seconds = float(sys.argv[1])
        env = dm_soccer.load(team_size=2, time_limit=10.0, walker_type=dm_soccer.WalkerType.BOXHEAD)
        dt = float(env.control_timestep())
        specs = env.action_spec()
        rng = np.random.default_rng(0)
        ts = env.reset()
        steps = max(1, round(seconds / dt))
        cpu, wall = time.process_time(), time.perf_counter()
        for _ in range(steps):
            ts = env.step([rng.uniform(s.minimum, s.maximum, s.shape) for s in specs])
            if ts.last():
                ts = env.reset()
        print(json.dumps({"steps": steps, "sim_seconds": steps * dt, "dt": dt, "agents": len(specs),
                          "cpu_s": time.process_time() - cpu, "wall_s": time.perf_counter() - wall,
                          "version": getattr(dm_control, "__version__", "?")}))
        """,
    ),
}


def simatch_row(scene: str, seconds: float) -> dict:
    import numpy as np

    import simatch.envs

    env = simatch.envs.parallel_env(scene)
    rng = np.random.default_rng(0)
    try:
        env.reset(seed=0)
        for _ in range(20):  # warm-up: compiled kernels
            env.step({a: rng.uniform(-1, 1, 6).astype(np.float32) for a in env.agents})
        env.reset(seed=1)
        dt = env.run.period
        steps = max(1, round(seconds / dt))
        cpu, wall = time.process_time(), time.perf_counter()
        for _ in range(steps):
            env.step({a: rng.uniform(-1, 1, 6).astype(np.float32) for a in env.agents})
            if not env.agents:
                env.reset()
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        return {"steps": steps, "sim_seconds": steps * dt, "dt": dt, "agents": len(env.possible_agents)} | {
            "cpu_s": cpu,
            "wall_s": wall,
        }
    finally:
        env.close()


def ensure_venv(root: Path, name: str, packages: list[str], install: bool) -> Path:
    python = root / name / "bin" / "python"
    marker = root / name / ".installed"
    if marker.exists():
        return python
    if not install:
        raise SystemExit(f"{root / name} is missing: run without --no-install to create it")
    print(f"creating {root / name} with {' '.join(packages)} ...", file=sys.stderr, flush=True)
    subprocess.run([sys.executable, "-m", "venv", str(root / name)], check=True)
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", *packages], check=True)
    marker.write_text(" ".join(packages) + "\n")
    return python


def peer_row(python: Path, program: str, *args: str) -> dict:
    env = {**os.environ, **ONE_THREAD}
    out = subprocess.run(
        [str(python), "-c", textwrap.dedent(program), *args], capture_output=True, text=True, env=env, timeout=3600
    )
    if out.returncode != 0:
        return {"error": out.stderr.strip().splitlines()[-1] if out.stderr.strip() else f"exit {out.returncode}"}
    return json.loads(out.stdout.strip().splitlines()[-1])


def figures(row: dict) -> dict:
    if "error" in row:
        return row
    return {
        **row,
        "steps_per_s": row["steps"] / row["wall_s"],
        "steps_per_cpu_s": row["steps"] / row["cpu_s"],
        "sim_s_per_cpu_s": row["sim_seconds"] / row["cpu_s"],
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0, help="simulated seconds per environment (default 60)")
    p.add_argument("--peers-dir", default=".venv-peers", help="where the peers' venvs live (default .venv-peers)")
    p.add_argument("--no-install", action="store_true", help="do not create missing venvs")
    p.add_argument("--only", action="append", default=[], help="only these rows (simatch, vmas, dm_control)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    if not args.seconds > 0:
        p.error("--seconds must be positive")
    os.environ.update(ONE_THREAD)
    rows: dict[str, dict] = {}
    wanted = set(args.only) or {"simatch", *PEERS}
    if "simatch" in wanted:
        for scene in ("msl_5v5", "striker_1v0"):
            rows[f"simatch {scene}"] = figures(simatch_row(scene, args.seconds))
    root = Path(args.peers_dir)
    for name, (packages, program) in PEERS.items():
        if name not in wanted:
            continue
        python = ensure_venv(root, name, packages, not args.no_install)
        if name == "vmas":
            rows["vmas football 5v5"] = figures(peer_row(python, program, str(args.seconds), "1"))
            rows["vmas football 5v5 x32 batched"] = figures(peer_row(python, program, str(args.seconds), "32"))
        else:
            rows["dm_control soccer 2v2"] = figures(peer_row(python, program, str(args.seconds)))
    if args.json:
        print(json.dumps(rows))
        return 0
    print(
        f"{'environment':32s} {'agents':>6s} {'dt [s]':>7s} {'steps/s':>9s} {'steps/cpu-s':>12s} {'sim-s/cpu-s':>12s}"
    )
    for name, r in rows.items():
        if "error" in r:
            print(f"{name:32s} failed: {r['error']}")
            continue
        print(
            f"{name:32s} {r['agents']:6d} {r['dt']:7.3f} {r['steps_per_s']:9.0f} {r['steps_per_cpu_s']:12.0f} "
            f"{r['sim_s_per_cpu_s']:12.1f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
