"""simatch: simulation of highly dynamic confrontations between multi-robot systems.

    import simatch
    sim = simatch.Simulation("msl_5v5", seed=1)
    sim.run(seconds=10.0)
    print(sim.result())

Subsystems: `simatch.sim` (simulation), `simatch.strategy` (strategy), `simatch.scene` (scene); they talk
through `simatch.bus` with the messages of `simatch.msgs` and read the scene file through `simatch.config`.
"""

from __future__ import annotations

__all__ = ["Simulation", "StateOverridden", "load_scene", "version"]


def version() -> str:
    """The installed distribution's version ("unknown" when run from a tree that was never installed)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _dist_version

    try:
        return _dist_version("simatch")
    except PackageNotFoundError:
        return "unknown"


def __getattr__(name: str):
    # lazy, so that light clients (e.g. a robot process importing simatch.msgs) do not load the physics
    if name in ("Simulation", "StateOverridden"):
        from . import simulation

        return getattr(simulation, name)
    if name == "load_scene":
        from .config.loader import load_scene

        return load_scene
    raise AttributeError(f"module 'simatch' has no attribute {name!r}")
