"""marchlab: a teaching toolkit for sphere tracing, Phong lighting, shadows and reflections.

The front door: the scene model (plain data), scene files, the camera model, `render` with a
choice of backend, and the `Frame` it returns. Backends are imported only when used.
"""

from .camera import camera_rays
from .errors import MarchlabError, SceneError
from .frame import Frame
from .render import BACKENDS, render
from .scene import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                    RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight)
from .scenefile import bundled_scene_names, load_scene, save_scene

__version__ = "0.1.0"

__all__ = ["camera_rays", "render", "load_scene", "save_scene", "bundled_scene_names", "Frame",
           "Scene", "Camera", "RenderSettings", "Material", "Checker", "PointLight",
           "DirectionalLight", "SpotLight", "Fog", "SkyBackground", "SolidBackground",
           "BACKENDS", "MarchlabError", "SceneError"]
