"""simatch: simulation of highly dynamic confrontations between multi-robot systems.

    import simatch
    sim = simatch.Simulation("msl_5v5", seed=1)
    sim.run(seconds=10.0)
    print(sim.result())

Subsystems: `simatch.sim` (simulation), `simatch.strategy` (strategy), `simatch.scene` (scene); they talk
through `simatch.bus` with the messages of `simatch.msgs`.
"""

from __future__ import annotations

__all__ = ["Simulation", "load_scene"]


def __getattr__(name: str):
    # lazy, so that light clients (e.g. a robot process importing simatch.msgs) do not load the physics
    if name == "Simulation":
        from .simulation import Simulation

        return Simulation
    if name == "load_scene":
        from .scene.loader import load_scene

        return load_scene
    raise AttributeError(f"module 'simatch' has no attribute {name!r}")
