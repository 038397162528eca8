"""Benchmarks (``simatch bench``): speed is measured here, never asserted by unit tests.

Each benchmark is a function ``run(seconds: float | None) -> dict`` whose keys go into the one JSON object
``simatch bench --json`` prints. They run one after another, each in a fresh process (see
`simatch.cli.bench`), on one core (the distributed ones start their team and robot processes).
"""

from __future__ import annotations

#: name -> "module:function", in the order they run
BENCHMARKS: dict[str, str] = {
    "physics": "simatch.bench.physics:run",
    "match": "simatch.bench.match:run",
    "record": "simatch.bench.record:run",
    "export": "simatch.bench.export:run",
    "referee": "simatch.bench.referee:run",
    "web": "simatch.bench.web:run",
    "encirclement": "simatch.bench.encirclement:run",
    "aerial": "simatch.bench.aerial:run",
    "distributed_rtt": "simatch.bench.distributed:rtt",
    "distributed_lockstep": "simatch.bench.distributed:lockstep",
    "distributed_realtime": "simatch.bench.distributed:realtime",
    "distributed_realtime_bus": "simatch.bench.distributed:realtime_bus",
    "tournament": "simatch.bench.tournament:run",
    "ros1": "simatch.bench.ros1:run",
    "ros2": "simatch.bench.ros2:run",
    "envs": "simatch.bench.envs:run",
}
