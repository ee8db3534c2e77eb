"""The paper's scenes as presets of the public API (docs/scenes.md)."""
from .base import ContactScene, Scene, SceneError
from .scenes import SCENES, Beam, Elastica, Plate, Ring, get_scene, parse_table, split_delta

__all__ = ["SCENES", "Beam", "ContactScene", "Elastica", "Plate", "Ring", "Scene", "SceneError", "get_scene",
           "parse_table", "split_delta"]
