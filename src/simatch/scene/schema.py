"""Moved to `simatch.config.schema` (the scene file and the game-command vocabulary are read by every subsystem,
so they live below them); this name stays so that existing plug-ins and scripts keep working."""

import sys

from ..config import schema as _moved

sys.modules[__name__] = _moved
