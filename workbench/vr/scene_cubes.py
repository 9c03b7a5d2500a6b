"""The lightbooth's surfaces as one hyperspectral cube (an atlas), for a bundle's level-2 texture.

The WebXR page shows the Scene page's lightbooth (:mod:`workbench.scene`): the
ColorChecker board, Ishihara plate :data:`~workbench.scene.images.SCENE_PLATE_NUMBER`
and the booth's grey walls. A runtime bundle carries level 2 only for the cubes
it was exported with (``export PROFILE --bundle DIR --cube FILE``), so these
surfaces are written as one cube first (:func:`write_scene_cube`, ``vr cube``),
side by side in one texture (:func:`atlas_layout`):

- the ColorChecker board texture of :func:`workbench.scene.images.scene_content`
  (24 patches of :data:`~workbench.scene.images.BOARD_PATCH_PX` texels, BabelColor
  average spectra, on a black frame of flat reflectance :data:`FRAME_REFLECTANCE`);
- the plate's card and dots, texel for texel, to its right;
- the wall's flat reflectance everywhere else (the page samples the strip ``wall``).

One cube rather than three because the bundle chooses its basis per cube:
fitted on the board, plate and wall together, the runtime texel equals the
full band's on 100 % of held-out texels (K + S = 21 + 4 on the simulated
headset); the plate alone, a handful of distinct spectra, got K = 5 and 89 %.

Bands: 380–780 nm every 4 nm (the paper's cubes, 101 bands), taken from the
scene's 1 nm spectra. The cube is named :data:`SCENE_CUBE` in the bundle (its
file's stem).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from workbench.colorimetry import WORKING_SHAPE

__all__ = [
    "SCENE_CUBE",
    "FRAME_REFLECTANCE",
    "atlas_layout",
    "scene_cube",
    "write_scene_cube",
]

SCENE_CUBE = "lightbooth"
"""The cube name the page looks for in a bundle (``export`` names a cube after its file's stem)."""

FRAME_REFLECTANCE = 0.03
"""Flat reflectance of the board's black frame (the ColorChecker's black plastic)."""

_STEP_NM = 4
_WALL_STRIP = 8


def atlas_layout() -> dict:
    """Where each surface lies in the cube: ``{name: [x, y, width, height]}`` in texels, row 0 at the top,
    plus ``size: [width, height]``."""
    from workbench.scene.images import scene_content

    content = scene_content()
    board_h, board_w = content.board_labels.shape
    plate_h, plate_w = content.plate_labels.shape
    width, height = board_w + plate_w + _WALL_STRIP, max(board_h, plate_h)
    return {"board": [0, 0, board_w, board_h], "plate": [board_w, 0, plate_w, plate_h],
            "wall": [board_w + plate_w, 0, _WALL_STRIP, _WALL_STRIP], "size": [width, height]}


def _bands(reflectances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every 4th nm of the scene's 1 nm spectra, 380–780 nm."""
    wavelengths = np.arange(WORKING_SHAPE.start, WORKING_SHAPE.end + 1, WORKING_SHAPE.interval)
    if reflectances.shape[-1] != wavelengths.size:
        raise ValueError(f"scene reflectances have {reflectances.shape[-1]} bands, expected "
                         f"{wavelengths.size} ({WORKING_SHAPE})")
    keep = (wavelengths - wavelengths[0]) % _STEP_NM == 0
    return reflectances[..., keep], wavelengths[keep]


def scene_cube():
    """The lightbooth atlas as a :class:`~workbench.hyperspectral.ReflectanceCube` (module doc)."""
    from workbench.hyperspectral import ReflectanceCube
    from workbench.scene.images import scene_content

    content = scene_content()
    layout = atlas_layout()
    board_spectra, wavelengths = _bands(np.asarray(content.board_reflectances, dtype=np.float64))
    plate_spectra, _ = _bands(np.asarray(content.plate_reflectances, dtype=np.float64))
    wall_spectrum, _ = _bands(np.asarray(content.wall_reflectance, dtype=np.float64))
    width, height = layout["size"]
    data = np.empty((height, width, wavelengths.size), dtype=np.float32)
    data[:] = wall_spectrum[0]
    frame = np.full((1, wavelengths.size), FRAME_REFLECTANCE)
    x, y, w, h = layout["board"]
    data[y:y + h, x:x + w] = np.vstack([frame, board_spectra])[np.asarray(content.board_labels) + 1]
    x, y, w, h = layout["plate"]
    data[y:y + h, x:x + w] = plate_spectra[np.asarray(content.plate_labels)]
    return ReflectanceCube(data, wavelengths, "lightbooth: ColorChecker board, Ishihara plate, grey wall")


def write_scene_cube(folder) -> Path:
    """Write :func:`scene_cube` as ``FOLDER/lightbooth.npz`` and return its path."""
    from workbench.hyperspectral import write_cube

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return write_cube(scene_cube(), folder / f"{SCENE_CUBE}.npz")
