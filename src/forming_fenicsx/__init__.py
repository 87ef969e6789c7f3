"""forming-fenicsx: steady-state strip extrusion and drawing by the flow formulation (Angelov
2014)."""
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.config.loader import load_scene
from forming_fenicsx.config.scene import Scene

__version__ = "0.1.0"
__all__ = ["Scene", "SceneError", "load_scene", "__version__"]
