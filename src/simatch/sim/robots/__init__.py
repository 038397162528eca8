"""Moved to `simatch.robots` (the robot models' public description, read by the simulator and the
judges); this name stays so that existing plug-ins and scripts keep working."""

import sys

from ... import robots as _moved

sys.modules[__name__] = _moved
