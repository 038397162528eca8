"""Judges, chosen by the scene's ``judge.kind``: a shipped name or ``"package.module:Class"``."""

from __future__ import annotations

from ...config.loader import LoadedScene, SceneError, validate_params
from ...plugins import PluginError, load
from .base import Judge, NoJudge, WorldControl

SHIPPED = {
    "none": "simatch.scene.judges.base:NoJudge",
    "locomotion_test": "simatch.scene.judges.locomotion:LocomotionTest",
    "msl_referee": "simatch.scene.referee:MslReferee",
    "encirclement": "simatch.scene.judges.encirclement:Encirclement",
    "drill": "simatch.scene.judges.drill:Drill",
    "flight_test": "simatch.scene.judges.flight:FlightTest",
    "pursuit": "simatch.scene.judges.pursuit:Pursuit",
}


def judge_class(kind: str, source: str = "scene") -> type[Judge]:
    """The Judge subclass a scene's ``judge.kind`` names (`SceneError` if none)."""
    try:
        cls = load(kind, SHIPPED, "judge")
    except PluginError as exc:
        raise SceneError(f"{source}: judge.kind: {exc}") from None
    if not (isinstance(cls, type) and issubclass(cls, Judge)):
        raise SceneError(f"{source}: judge.kind: {kind!r} is not a simatch.scene.judges.Judge subclass")
    return cls


def make_judge(scene: LoadedScene, world: WorldControl) -> Judge:
    spec = scene.spec.judge
    cls = judge_class(spec.kind, scene.source)
    extra = dict(spec.model_extra or {})
    params = validate_params(cls.Params, extra, scene.source, "judge")
    return cls(scene, params, world)


__all__ = ["Judge", "NoJudge", "SHIPPED", "WorldControl", "judge_class", "make_judge"]
