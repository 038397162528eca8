"""Scene files: the configuration of a run (schema, loader, the shipped scenes), read by every subsystem.

A scene file says which world, which teams with which robot models and strategies, which judge and which
timing; it is not the paper's *scene subsystem* (`simatch.scene`: game commands, coaches, referee, judges),
which is one of its readers.
"""

from .loader import LoadedScene, SceneError, check_models, load_scene, scene_from_text, shipped_scenes
from .schema import Scene

__all__ = ["LoadedScene", "Scene", "SceneError", "check_models", "load_scene", "scene_from_text", "shipped_scenes"]
