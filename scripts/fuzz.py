#!/usr/bin/env python3
"""The fuzzing campaign: every target of tests/fuzz/targets.py for a time, with a count of inputs, crashes and
coverage.

    .venv/bin/python scripts/fuzz.py --minutes 10                     # every target, 10 minutes in all
    nice .venv/bin/python scripts/fuzz.py --minutes 60 --json         # a long campaign (the machine is shared)
    .venv/bin/python scripts/fuzz.py --targets cdr --engine atheris --minutes 5
    .venv/bin/python scripts/fuzz.py --replay fuzz-out/crashes/cdr-1.bin   # run one saved crash again

Each input is a buffer of bytes that Hypothesis turns into the target's structured input
(``fuzz_one_input``): with ``--engine hypothesis`` (the default) the buffers are random (seeded: ``--seed``);
with ``--engine atheris`` each target runs in a process of its own under atheris (libFuzzer), which mutates
the buffers guided by the coverage of the Python code it instruments (simatch's modules). A **crash** is an
exception other than the input's documented error, a disagreement the target checks (the C and Python CDR
decoders), a corrupted physics state (NaN, a robot outside the world) or a **hang** (one input running longer
than ``--hang`` seconds); each is saved (the buffer, and its traceback) under ``OUT/crashes/`` and can be run
again with ``--replay``. Coverage is the share of the lines of the targets' modules (`MODULES`) the campaign
ran (with ``coverage``, for the hypothesis engine; the C extension's own lines are not measured).

Exit status 0 when no crash was found, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


class Hang(Exception):
    """One input ran longer than allowed."""


def _alarm(signum, frame):
    raise Hang("the input ran longer than the hang limit")


def _targets(names: list[str] | None):
    from tests.fuzz.targets import TARGETS

    if names:
        unknown = set(names) - set(TARGETS) - {"selftest"}
        if unknown:
            raise SystemExit(f"fuzz.py: unknown target(s) {', '.join(sorted(unknown))}; targets: {', '.join(TARGETS)}")
        chosen = {n: TARGETS[n] for n in names if n in TARGETS}
        if "selftest" in names:
            chosen["selftest"] = _selftest()
        return chosen
    return dict(TARGETS)


def _selftest():
    """A target that crashes and hangs on purpose (to check that the campaign finds and saves both)."""
    from hypothesis import strategies as st
    from tests.fuzz.targets import Target

    def prop(n):
        if n == 7:
            raise ZeroDivisionError("the selftest's crash")
        if n == 9:
            time.sleep(60)

    return Target(prop, st.integers(0, 10))


def _test(target):
    return target.test(max_examples=1)


def campaign(args) -> dict:
    targets = _targets(args.targets.split(",") if args.targets else None)
    out = Path(args.out)
    (out / "crashes").mkdir(parents=True, exist_ok=True)
    cov = None
    if args.coverage and args.engine == "hypothesis":
        try:
            import coverage
            from tests.fuzz.targets import MODULES

            src = ROOT / "src"
            cov = coverage.Coverage(include=[str(src / m) for m in MODULES], data_file=None, branch=False)
        except ImportError:
            print("fuzz.py: `coverage` is not installed: no coverage figures", file=sys.stderr)
    report = {"engine": args.engine, "seed": args.seed, "seconds": args.minutes * 60, "targets": {}}
    budget = args.minutes * 60.0 / max(1, len(targets))
    rng = random.Random(args.seed)
    if cov is not None:
        cov.start()
    try:
        for name, target in targets.items():
            say(args, f"{name}: {budget:.0f} s")
            if args.engine == "atheris":
                report["targets"][name] = _atheris(args, name, budget, out)
            else:
                report["targets"][name] = _hypothesis(args, name, target, budget, rng, out)
    finally:
        if cov is not None:
            cov.stop()
    if cov is not None:
        report["coverage"] = _coverage(cov)
    report["inputs"] = sum(t["inputs"] for t in report["targets"].values())
    report["crashes"] = sum(len(t["crashes"]) for t in report["targets"].values())
    return report


def _hypothesis(args, name: str, target, budget: float, rng: random.Random, out: Path) -> dict:
    from tests.fuzz.targets import COUNTS

    fuzz = _test(target).hypothesis.fuzz_one_input
    stats = {"inputs": 0, "examples": 0, "crashes": [], "seconds": 0.0}
    # the first input imports the target's modules and builds what it reuses (on a loaded machine that can
    # take longer than the hang limit): done before the clock starts, without the hang alarm
    try:
        fuzz(bytes(64))
    except Exception:
        pass  # (an input like any other: the campaign meets it again)
    counted = COUNTS[name]
    seen: set[str] = set()
    previous = signal.signal(signal.SIGALRM, _alarm)
    t0 = time.monotonic()
    try:
        while time.monotonic() - t0 < budget:
            buffer = rng.randbytes(rng.choice((16, 64, 256, 1024, 4096)))
            signal.setitimer(signal.ITIMER_REAL, args.hang)
            try:
                fuzz(buffer)
            except (Hang, Exception) as exc:
                signal.setitimer(signal.ITIMER_REAL, 0)
                kind = "hang" if isinstance(exc, Hang) else type(exc).__name__
                where = _where(exc)
                key = f"{kind}@{where}"
                if key not in seen:  # one report per distinct crash (kind and place)
                    seen.add(key)
                    path = out / "crashes" / f"{name}-{len(stats['crashes']) + 1}.bin"
                    path.write_bytes(buffer)
                    path.with_suffix(".txt").write_text("".join(traceback.format_exception(exc)))
                    stats["crashes"].append(
                        {"kind": kind, "where": where, "message": str(exc)[:300], "file": str(path)}
                    )
                    say(args, f"  CRASH {kind} at {where}: {str(exc)[:120]} (saved {path})")
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
            stats["examples"] += 1
    finally:
        signal.signal(signal.SIGALRM, previous)
    # inputs: what the target tried (an example is a seed and its variants); a target that does not count
    # its inputs (the selftest) tried one per example
    stats["inputs"] = (COUNTS[name] - counted) or stats["examples"]
    stats["seconds"] = round(time.monotonic() - t0, 1)
    stats["inputs_per_second"] = round(stats["inputs"] / max(stats["seconds"], 1e-9), 1)
    return stats


def _where(exc: BaseException) -> str:
    """file:line of the innermost frame in simatch or the targets (where the crash is)."""
    tb = exc.__traceback__
    place = "?"
    while tb is not None:
        f = tb.tb_frame.f_code.co_filename
        if "simatch" in f or "fuzz" in f:
            place = f"{Path(f).name}:{tb.tb_lineno}"
        tb = tb.tb_next
    return place


def _coverage(cov) -> dict:
    data = cov.get_data()
    out, total_run, total_lines = {}, 0, 0
    for path in sorted(data.measured_files()):
        try:
            _, statements, _, missing, _ = cov.analysis2(path)
        except Exception:
            continue
        run = len(statements) - len(missing)
        out[str(Path(path).relative_to(ROOT / "src"))] = round(100.0 * run / max(1, len(statements)), 1)
        total_run += run
        total_lines += len(statements)
    return {"lines_percent": round(100.0 * total_run / max(1, total_lines), 1), "by_module": out}


# --- atheris -------------------------------------------------------------------------------------------------------
def _atheris(args, name: str, budget: float, out: Path) -> dict:
    crashes = out / "crashes" / f"{name}-atheris-"
    cmd = [sys.executable, __file__, "--atheris-worker", name, f"-max_total_time={max(1, int(budget))}"]
    cmd += [
        "-print_final_stats=1",
        f"-artifact_prefix={crashes}",
        f"-seed={args.seed or 1}",
        f"-timeout={int(args.hang)}",
    ]
    tally = out / f"atheris-{name}.count"
    env = dict(os.environ, SIMATCH_FUZZ_TALLY=str(tally))
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=budget + 600, env=env)
    examples = 0
    for line in proc.stderr.splitlines():
        if line.startswith("stat::number_of_executed_units:"):
            examples = int(line.split(":")[-1])
    inputs = int(tally.read_text()) if tally.exists() else 0  # (counted to within the last half second)
    found = []
    if proc.returncode != 0:
        tail = proc.stderr[-2000:]
        found.append({"kind": "atheris", "where": "", "message": tail, "file": str(crashes) + "*"})
        say(args, f"  CRASH under atheris (exit {proc.returncode}): {tail[-300:]}")
    return {"inputs": inputs or examples, "examples": examples, "crashes": found, "seconds": round(budget, 1)}


def atheris_worker(name: str, libfuzzer_args: list[str]) -> None:
    import atheris

    with atheris.instrument_imports(include=["simatch"]):
        import simatch  # noqa: F401  (its modules instrumented for coverage feedback)
        from simatch.msgs import cdr  # noqa: F401
    from tests.fuzz.targets import COUNTS

    target = _targets([name])[name]
    fuzz = _test(target).hypothesis.fuzz_one_input
    tally = Path(os.environ["SIMATCH_FUZZ_TALLY"])
    last = [0.0]

    def one(buffer: bytes) -> None:
        try:
            fuzz(buffer)
        finally:  # libFuzzer ends the process without Python's exit handlers: the count is kept as it goes
            now = time.monotonic()
            if now - last[0] > 0.5:
                last[0] = now
                tally.write_text(str(COUNTS[name]))

    atheris.Setup([sys.argv[0], *libfuzzer_args], one)
    atheris.Fuzz()


# --- the command ----------------------------------------------------------------------------------------------------
def say(args, text: str) -> None:
    if not args.json:
        print(text, file=sys.stderr, flush=True)


def replay(args) -> int:
    path = Path(args.replay)
    name = path.name.split("-")[0]
    target = _targets([name])[name]
    try:
        _test(target).hypothesis.fuzz_one_input(path.read_bytes())
    except Exception:
        traceback.print_exc()
        return 1
    print(f"{path}: no crash")
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--atheris-worker"]:
        atheris_worker(argv[1], argv[2:])
        return 0
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--minutes", type=float, default=1.0, help="length of the whole campaign (default 1)")
    p.add_argument("--targets", help="comma-separated targets (default: all)")
    p.add_argument("--engine", choices=("hypothesis", "atheris"), default="hypothesis")
    p.add_argument("--seed", type=int, default=0, help="seed of the random buffers (default 0)")
    p.add_argument("--hang", type=float, default=30.0, help="seconds after which one input counts as a hang")
    p.add_argument("--no-coverage", dest="coverage", action="store_false", help="no coverage (faster)")
    p.add_argument("--out", default="fuzz-out", help="folder for crashes (default fuzz-out)")
    p.add_argument("--replay", metavar="FILE.bin", help="run one saved crash again")
    p.add_argument("--json", action="store_true", help="print one JSON report")
    args = p.parse_args(argv)
    if args.replay:
        return replay(args)
    report = campaign(args)
    if args.json:
        print(json.dumps(report))
    else:
        for name, t in report["targets"].items():
            print(
                f"{name:10s} {t['inputs']:>10d} inputs ({t.get('examples', '-')} examples)  "
                f"{len(t['crashes'])} crash(es)  {t['seconds']:.0f} s"
            )
        print(f"{'total':10s} {report['inputs']:>10d} inputs  {report['crashes']} crash(es)")
        if "coverage" in report:
            print(f"coverage: {report['coverage']['lines_percent']} % of the lines of the targets' modules")
    return 1 if report["crashes"] else 0


if __name__ == "__main__":
    os.environ.setdefault("SIMATCH_FUZZ", "1")
    sys.exit(main())
