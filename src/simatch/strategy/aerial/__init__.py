"""Strategies of the scenes with aerial robots: the aerial encirclement (ground chasers and scouting drones
against targets among obstacles) and the 3D pursuit-evasion of drones."""

from .encircle import AerialChasers, Evader, GroundChaser, Scout
from .pursuit import Chase, Evader3D, Pincer

__all__ = ["AerialChasers", "Chase", "Evader", "Evader3D", "GroundChaser", "Pincer", "Scout"]
