"""The 3D scene preview, without Qt: a virtual lightbooth with a ColorChecker and an Ishihara plate.

- :mod:`.images` — what each view shows for a source, profile and level
  (numpy only).
- :mod:`.errors` — the per-patch error table (the paper's Table 4 per patch).
- :mod:`.booth` — the pyvista meshes, built once and re-lit in place; renders
  with ``pyvista.Plotter(off_screen=True)`` as well as in the window.

``booth`` imports pyvista; import it explicitly (``from workbench.scene.booth
import build_booth``) so the Qt-free, VTK-free parts stay light.
"""

from workbench.scene.errors import PatchError, SourceErrors, patch_errors
from workbench.scene.images import (
    LEVELS,
    LevelImages,
    SceneContent,
    board_patch_centre_uv,
    headset_to_monitor_rgb8,
    level_images,
    scene_content,
)

__all__ = [
    "LEVELS",
    "LevelImages",
    "SceneContent",
    "PatchError",
    "SourceErrors",
    "board_patch_centre_uv",
    "headset_to_monitor_rgb8",
    "level_images",
    "patch_errors",
    "scene_content",
]
