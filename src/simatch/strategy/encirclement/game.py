"""What the encirclement judge tells everybody, as a robot reads it from its WorldModel.

The judge publishes its picture of the game on ``game_state`` (GameState); its ``result`` field carries the
judge's summary as JSON, including every capture: ``{"captures": [{"robot": "magenta/3", "x": .., "y": ..,
"t": ..}, ...], ...}`` (world frame). Robots learn who is captured from this topic only.
"""

from __future__ import annotations

import json


class Captures:
    """The captured robots as one robot knows them: names, and where they stand in its team frame."""

    def __init__(self) -> None:
        self._source: str | None = None
        self.names: frozenset[str] = frozenset()
        self.where: list[tuple[float, float]] = []

    def update(self, world) -> Captures:
        """Re-read the judge's latest GameState if it changed (parsing only when it did)."""
        game = world.game
        text = game.result if game is not None else None
        if text is self._source or text == self._source:
            return self
        self._source = text
        names, where = [], []
        try:
            for c in json.loads(text or "{}").get("captures", ()):
                names.append(str(c["robot"]))
                where.append((world.sign * float(c["x"]), world.sign * float(c["y"])))
        except (ValueError, TypeError, KeyError, AttributeError):
            names, where = [], []  # a malformed summary tells nothing: nobody is known to be captured
        self.names = frozenset(names)
        self.where = where
        return self

    def free(self, positions: list[tuple[float, float]], tolerance: float = 0.3) -> list[tuple[float, float]]:
        """The ``positions`` that are not where a captured robot stands."""
        if not self.where:
            return positions
        t2 = tolerance * tolerance
        return [(x, y) for x, y in positions if all((x - cx) ** 2 + (y - cy) ** 2 > t2 for cx, cy in self.where)]
