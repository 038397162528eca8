"""The encirclement scene's strategies (paper section VII-C): chasers that round targets up into a prison
(``encircle``, `Chaser`) and targets that flee (``flee``, `Target`)."""

from .chasers import Chaser, ChaserParams
from .targets import Target, TargetParams

__all__ = ["Chaser", "ChaserParams", "Target", "TargetParams"]
