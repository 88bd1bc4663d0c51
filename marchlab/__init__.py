"""marchlab: a teaching toolkit for sphere tracing, Phong lighting, shadows and reflections.

The front door: `render` with a choice of backend, `probe` for one pixel's march, and the scene model's everyday names
(`Scene`, `load_scene`, `Frame`, ...; they live in `scene_model`). Backends are imported only
when used; the command line, comparisons, simulation and reports are modules of their own.
"""

from scene_model.camera import camera_rays
from scene_model.errors import MarchlabError, SceneError
from scene_model.frame import Frame
from scene_model.scene import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                               RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight,
                               Texture)
from scene_model.scenefile import bundled_scene_names, load_scene, save_scene

from .probe import probe
from .render import BACKENDS, render

__version__ = "0.1.0"

__all__ = ["camera_rays", "render", "probe", "load_scene", "save_scene", "bundled_scene_names", "Frame",
           "Scene", "Camera", "RenderSettings", "Material", "Checker", "Texture", "PointLight",
           "DirectionalLight", "SpotLight", "Fog", "SkyBackground", "SolidBackground",
           "BACKENDS", "MarchlabError", "SceneError"]
