"""The bus: one publish/subscribe interface (`Bus`), its transports, topic names and the lockstep clock."""

from . import topics
from .base import Bus, BusStats
from .inproc import InProcessBus
from .node import LockstepClock, Node, NodeContext, Phase, stable_seed

__all__ = ["Bus", "BusStats", "InProcessBus", "LockstepClock", "Node", "NodeContext", "Phase", "stable_seed", "topics"]
