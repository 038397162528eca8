"""A ROS 2 domain of one's own on this machine, for the tests and the benchmark (no rclpy import).

DDS participants of the same ``ROS_DOMAIN_ID`` find each other: two test sessions (or a benchmark and a test
session) on one machine must not share one. `claim` takes a domain nobody else here holds, by an advisory
lock on a file per domain in the temporary folder, held until the returned file is closed (or the process
ends), and sets ``ROS_DOMAIN_ID`` and discovery on this machine only for this process and its children.
"""

from __future__ import annotations

import fcntl
import os
import random
import tempfile
from typing import IO

#: the domains handed out (0 is everybody's default; 0..232 are valid ids)
FIRST, LAST = 100, 219


def claim(first: int = FIRST, last: int = LAST) -> tuple[int, IO]:
    """(domain id, the open lock file: keep it open while the domain is used)."""
    folder = os.path.join(tempfile.gettempdir(), f"simatch-ros2-domains-{os.getuid()}")
    os.makedirs(folder, exist_ok=True)
    for domain in random.sample(range(first, last + 1), last - first + 1):
        f = open(os.path.join(folder, str(domain)), "a")  # noqa: SIM115 (held open by the caller)
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        os.environ["ROS_DOMAIN_ID"] = str(domain)
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        return domain, f
    raise RuntimeError(f"every ROS 2 domain {first}..{last} is taken on this machine")
