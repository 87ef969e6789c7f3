"""forming-fenicsx: steady-state strip extrusion and drawing by the flow formulation (Angelov 2014)."""
from .errors import SceneError
from .scene import Scene, load_scene

__version__ = "0.1.0"
__all__ = ["Scene", "SceneError", "load_scene", "__version__"]
