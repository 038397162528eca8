"""Fixtures of the distributed tests (helpers in `cluster`)."""

from __future__ import annotations

import pytest

from .cluster import Processes


@pytest.fixture
def procs(tmp_path):
    """Starts simatch processes for one test; none outlives it."""
    ps = Processes(tmp_path)
    try:
        yield ps
    finally:
        ps.close()
