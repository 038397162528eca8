"""Shared fixtures: every test talks to the real parts (real MuJoCo, real buses, real processes)."""

from __future__ import annotations

import math
import os
import shutil
import signal
from pathlib import Path

import pytest

# Bound kernels check every argument against its declared type in the tests (simatch.compiled): a wrong
# dtype or a strided view is a TypeError here, where a production run would read wrong memory. Set before
# simatch is imported, and inherited by the processes the tests start.
os.environ.setdefault("SIMATCH_CHECK_KERNELS", "1")

import simatch  # noqa: E402

# A suite started in the background by a non-interactive shell (as CI may start it) inherits SIGINT ignored;
# Python then installs no KeyboardInterrupt handler, here or in the processes the tests start, and the tests
# of Ctrl-C see nothing. Give this process Python's handler: the processes it starts then get the default.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def empty_field(**overrides):
    """The msl_5v5 world with every robot idle (no strategies, no referee) unless overrides say otherwise."""
    base = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": "none"}
    base.update(overrides)
    return base


@pytest.fixture
def field_sim():
    """A Simulation of the msl_5v5 world with idle robots; the test drives what it needs."""
    sims = []

    def make(seed: int = 0, **overrides):
        sim = simatch.Simulation("msl_5v5", seed=seed, overrides=empty_field(**overrides))
        sims.append(sim)
        return sim

    yield make
    for sim in sims:
        sim.close()


def park_everyone_but(sim, keep: list[str]):
    """Move every robot not in ``keep`` to the side line, out of the way."""
    x = -10.0
    for name in sim.simulator.robot_names:
        if name not in keep:
            sim.set_model_state(name, x=x, y=-7.8, yaw=0.0, vx=0.0, vy=0.0, wz=0.0)
            x += 0.8


def heading(vx: float, vy: float) -> float:
    return math.atan2(vy, vx)


CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    # WebGL without a GPU (the 3D view): Chromium's software renderer, SwiftShader, through ANGLE
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
]


@pytest.fixture(scope="session")
def browser():
    """One headless chromium for the whole session (Playwright's sync API allows one per process; each launch
    gets a fresh, empty profile): the web UI's pages and the reports are opened in it."""
    from playwright import sync_api

    if not Path(CHROMIUM).exists():
        pytest.fail("Debian's chromium is missing: run scripts/install-system-deps.sh")
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS, timeout=60_000)
        try:
            yield b
        finally:
            b.close()
