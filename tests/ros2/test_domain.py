"""simatch.ros2.domain: two sessions on one machine never get the same ROS 2 domain (checked with separate
processes, as two test sessions or a test session and a benchmark are)."""

from __future__ import annotations

import subprocess
import sys

#: a process that claims a domain of 225..226, says which, and holds it until its stdin closes
HOLDER = """
import sys
from simatch.ros2 import domain
try:
    got, lock = domain.claim(225, 226)
except RuntimeError as exc:
    print("error", exc, flush=True)
    sys.exit(3)
import os
print(got, os.environ["ROS_DOMAIN_ID"], os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"], flush=True)
sys.stdin.read()
"""


def _holder() -> tuple[subprocess.Popen, str]:
    p = subprocess.Popen([sys.executable, "-c", HOLDER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    return p, p.stdout.readline().strip()


def test_each_session_gets_a_domain_nobody_else_holds():
    procs = []
    try:
        a, said_a = _holder()
        b, said_b = _holder()
        procs += [a, b]
        da, db = said_a.split()[0], said_b.split()[0]
        assert {da, db} == {"225", "226"}, (said_a, said_b)
        assert said_a.split()[1:] == [da, "LOCALHOST"]  # this process and its children use it, on this machine
        c, said_c = _holder()
        procs.append(c)
        assert c.wait(30) == 3 and "every ROS 2 domain 225..226 is taken" in said_c, said_c
        a.stdin.close()  # the first session ends: its domain is free again
        assert a.wait(30) == 0
        d, said_d = _holder()
        procs.append(d)
        assert said_d.split()[0] == da
    finally:
        for p in procs:
            if p.poll() is None:
                p.stdin.close()
                p.wait(30)
