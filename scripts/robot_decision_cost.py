"""What one robot's decision costs when it is the only robot of its team in its process (as in a
distributed run with one process per robot), against the embedded run where a team's robots share the
team picture.

Runs the shipped msl_5v5 match twice in this process: once as shipped (``nubot``: a team's robots share
one team picture per tick) and once with every robot alone (``simatch.strategy.nubot:NubotRobot``: each
robot computes its own team picture, as a robot process does). Both runs must give the same
state_digest (sharing is only a cache); the output is each run's decision time per robot and control
tick, and how many team pictures a robot computes per simulated second.

    python scripts/robot_decision_cost.py [--seconds 30] [--seed 1] [--json]
"""

from __future__ import annotations

import argparse
import json
import time

from simatch import Simulation
from simatch.bench.match import timed_decisions
from simatch.config.loader import load_scene
from simatch.strategy.node import RobotNode

WARM_UP = 5.0
LONE = "simatch.strategy.nubot:NubotRobot"


def measure(lone: bool, seconds: float, seed: int) -> dict:
    overrides = {"teams.cyan.strategy": LONE, "teams.magenta.strategy": LONE} if lone else {}
    scene = load_scene("msl_5v5", overrides)
    with Simulation(scene, seed=seed) as sim:
        sim.run(seconds=WARM_UP, until_done=False)
        nodes = [n for n in sim.robot_nodes.values() if isinstance(n, RobotNode)]
        spent = timed_decisions(sim, time.process_time)
        shared = {id(n.strategy.shared): n.strategy.shared for n in nodes}
        pictures0 = sum(s.evaluated for s in shared.values())
        sim.run(seconds=seconds, until_done=False)
        ticks = seconds / scene.spec.control.period
        pictures = sum(s.evaluated for s in shared.values()) - pictures0
        digest = sim.state_digest()
    return {
        "mode": "lone" if lone else "team",
        "decide_us_per_robot_tick": round(spent[0] / (ticks * len(nodes)) * 1e6, 1),
        "team_pictures_per_robot_per_s": round(pictures / len(nodes) / seconds, 1),
        "state_digest": digest,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = [measure(False, args.seconds, args.seed), measure(True, args.seconds, args.seed)]
    same = rows[0]["state_digest"] == rows[1]["state_digest"]
    if args.json:
        print(json.dumps({"runs": rows, "same_digest": same}))
        return
    for r in rows:
        print(
            f"{r['mode']:5s} decide {r['decide_us_per_robot_tick']:6.1f} us per robot tick, "
            f"{r['team_pictures_per_robot_per_s']:5.1f} team pictures per robot per s"
        )
    print("same state_digest" if same else "DIFFERENT state_digest: sharing the team picture changed the match")


if __name__ == "__main__":
    main()
