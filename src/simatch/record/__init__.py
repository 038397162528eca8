"""Recording every game as a dataset, and playing it back (issue 6).

* `Recorder` (``simatch run --record FILE.mcap``): every topic of a run's bus, the metadata that
  reproduces it and a Foxglove 3D scene, in one rosbag2-compatible MCAP file, written second by second.
* `Recording`: reads a recording, whole, cut short or damaged.
* `Player` (``simatch replay FILE``): publishes a recording on a bus again, with its timing.
* `verify` (``simatch replay FILE --verify``): re-simulates a recording and compares it bit for bit.
* `export` (``simatch export FILE``): tidy Parquet or CSV tables.

    import simatch
    from simatch.record import Recorder, verify
    with simatch.Simulation("msl_5v5", seed=1) as sim, Recorder.for_run(sim, "match.mcap"):
        sim.run(seconds=10.0)
    print(verify("match.mcap").describe())
"""

from __future__ import annotations

import importlib

_WHERE = {
    "ExportError": "tables",
    "export": "tables",
    "Player": "player",
    "Recording": "reader",
    "RecordingError": "reader",
    "RecordError": "recorder",
    "Recorder": "recorder",
    "Verdict": "reproduce",
    "VerifyError": "reproduce",
    "verify": "reproduce",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    # lazy: `simatch run` loads the --record extension to list its options; the writer, the reader and
    # pyarrow load only when used
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'simatch.record' has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
