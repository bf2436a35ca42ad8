"""Scene configuration: TOML -> frozen, validated dataclasses."""
from .base import ConfigError
from .scene import Scene, load_scene, scene_from_dict

__all__ = ["ConfigError", "Scene", "load_scene", "scene_from_dict"]
