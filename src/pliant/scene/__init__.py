"""Scene files (TOML): mesh, materials per region, constraints and loads with load curves, solver
settings and outputs. ``load_scene(path)`` validates everything and returns a :class:`Scene` whose
``builder`` is ready to finalize. Unknown keys are errors that name the file, key and line.

See docs/scenes.md for the full reference, and examples/ for complete scenes.
"""

from ..job import Scene
from .keys import get_key, set_key
from .loader import load_scene, make_curve
from .schema import SceneError

__all__ = ["Scene", "load_scene", "SceneError", "make_curve", "get_key", "set_key"]
