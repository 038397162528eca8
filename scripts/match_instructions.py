#!/usr/bin/env python3
"""Count the machine instructions a stretch of the shipped match costs: a speed figure that does not
depend on what else the machine is doing (valgrind's callgrind counts instructions, not seconds).

On a machine shared with other work, wall-clock and even CPU-time figures of the same code move by tens of
percent from run to run; the instruction count of the same code and inputs is the same to a few parts in
a million. It is not time (an instruction of the interpreter and one of MuJoCo's or a compiled kernel's
inner loop take different times), but a change that saves Python work shows as fewer instructions, on any
load. Compare two trees by running this script in each.

The script runs itself under ``valgrind --tool=callgrind`` with instrumentation off; after the warm-up
(the kernels loaded as ``simatch bench`` loads them, then the match's first ``--warm-up`` seconds) it
switches counting on with ``callgrind_control``, plays ``--seconds`` more, switches it off, and prints
instructions per simulated second (and the run's state digest, to check that two trees played the same
match). Slow: valgrind runs the program some fifty times slower (about 12 minutes for the default 20 s).
With ``--record`` the match is recorded (as ``simatch run --record`` does, the recorder attached before the
first step): the difference from a run without it is what the recording costs the simulation's process (its
writer process runs outside valgrind and is not counted).

    python scripts/match_instructions.py [--seconds 20] [--seed 1] [--record] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

INSIDE = "SIMATCH_UNDER_CALLGRIND"


def measure(seconds: float, seed: int, warm_up: float, record: bool) -> str:
    """Runs inside valgrind: plays the match, counting only the measured stretch; returns its digest."""
    from simatch import Simulation
    from simatch.bench.match import load_kernels
    from simatch.config.loader import load_scene
    from simatch.record import Recorder

    scene = load_scene("msl_5v5")
    load_kernels(scene)
    with tempfile.TemporaryDirectory() as tmp, Simulation(scene, seed=seed) as sim:
        recorder = Recorder.for_run(sim, os.path.join(tmp, "match.mcap"), command_line=[]) if record else None
        sim.run(seconds=warm_up, until_done=False)
        pid = str(os.getpid())
        subprocess.run(["callgrind_control", "-i", "on", pid], capture_output=True, check=True)
        sim.run(seconds=seconds, until_done=False)
        subprocess.run(["callgrind_control", "-i", "off", pid], capture_output=True, check=True)
        if recorder is not None:
            recorder.close()
        return sim.state_digest()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="simulated seconds counted (default 20)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--warm-up", type=float, default=5.0, help="simulated seconds played first, not counted")
    ap.add_argument("--record", action="store_true", help="record the match (the recording's cost is counted)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    if not args.seconds > 0 or args.warm_up < 0:
        ap.error("--seconds must be positive and --warm-up not negative")
    if os.environ.get(INSIDE):
        print(json.dumps({"digest": measure(args.seconds, args.seed, args.warm_up, args.record)}))
        return 0
    if shutil.which("valgrind") is None or shutil.which("callgrind_control") is None:
        ap.error("needs valgrind (Debian: apt-get install valgrind)")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        keep = os.environ.get("SIMATCH_CALLGRIND_OUT")  # keep the profile (for callgrind_annotate) there
        cmd = ["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={keep or out}"]
        cmd += [sys.executable, os.path.abspath(__file__), *(argv if argv is not None else sys.argv[1:])]
        print(f"counting {args.seconds:g} s of msl_5v5 (seed {args.seed}) under callgrind ...", file=sys.stderr)
        proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, INSIDE: "1"})
        if proc.returncode != 0:
            print(proc.stderr[-3000:], file=sys.stderr)
            return 1
        refs = re.findall(r"I\s+refs:\s+([\d,]+)", proc.stderr)
        if not refs:
            print(proc.stderr[-3000:], file=sys.stderr)
            return 1
        total = int(refs[-1].replace(",", ""))
        digest = json.loads(proc.stdout.strip().splitlines()[-1])["digest"]
    result = {
        "match_instructions": total,
        "match_instructions_per_sim_second": round(total / args.seconds),
        "seconds": args.seconds,
        "seed": args.seed,
        "recorded": args.record,
        "state_digest": digest,
    }
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:36s} {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
