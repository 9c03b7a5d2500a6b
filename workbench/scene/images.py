"""What the scene's two views show: the ColorChecker board and an Ishihara plate at level 1 and 2.

The engine model of design §2 decides each texel's frame-buffer value
(``engine_render(texture, light)``), the headset profile turns that DAC into
the light it emits (``display.forward``), and the preview shows that colour on
this (ideal sRGB) monitor with the headset white mapped to the monitor white
(:func:`headset_to_monitor_rgb8`). So a view is what the headset would show,
texel for texel:

- **level 1**: the light is the source's level-1 light colour, the textures
  stay as authored (the ColorChecker: the manufacturer's sRGB, as the paper's
  scanned texture and its Table 4; the plate: the exact sRGB of each dot under D65);
- **level 2**: the textures are re-authored for the source
  (:func:`workbench.colour_management.level2_texture`).

Images are computed per *label* (a patch or a dot) and expanded through label
images that never change, so switching the source costs a few milliseconds.
No Qt, no VTK here: :mod:`workbench.scene.booth` puts the images on meshes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from workbench.colorimetry import DEFAULT_K
from workbench.colour_management import (
    authored_srgb8,
    engine_render,
    level2_texture,
    light_colour,
)
from workbench.display import DisplayModel, SRGBDisplay
from workbench.errors import InputError
from workbench.samples import COLORCHECKER_SRGB_REFERENCE, colorchecker

__all__ = [
    "LEVELS",
    "BOARD_PATCH_PX",
    "BOARD_GAP_PX",
    "BOOTH_WALL_REFLECTANCE",
    "SCENE_PLATE_NUMBER",
    "SceneContent",
    "LevelImages",
    "scene_content",
    "headset_to_monitor_rgb8",
    "level_images",
    "board_patch_centre_uv",
]

LEVELS = (1, 2)
"""The colour-management levels a view can show."""

BOARD_PATCH_PX = 40
"""Side of one ColorChecker patch in the board texture (pixels)."""

BOARD_GAP_PX = 8
"""Black frame between patches (pixels)."""

BOOTH_WALL_REFLECTANCE = 0.45
"""Spectrally flat reflectance of the booth's grey walls (a mid-grey, Munsell N5-like)."""

SCENE_PLATE_NUMBER = 3
"""Plate of the paper's set in the booth (a transformation plate, in the paper's own colours)."""


@dataclass(frozen=True, eq=False)
class SceneContent:
    """The surfaces in the booth, independent of source and profile.

    Attributes
    ----------
    board_labels : ndarray (H, W) of int
        Patch index per texel of the board texture, -1 on the black frame.
    board_reflectances : ndarray (24, 401)
    board_authored_rgb8 : ndarray (24, 3)
        Level-1 texture of each patch (the manufacturer's sRGB).
    patch_names : tuple of str
    plate_labels : ndarray (S, S) of int
        Label per texel of the plate texture: 0 = card, ``i`` = dot ``i - 1``.
    plate_reflectances : ndarray (N + 1, 401)
        The card, then each dot.
    plate_authored_rgb8 : ndarray (N + 1, 3)
        Level-1 texture of the card and each dot (its exact sRGB under D65).
    wall_reflectance : ndarray (1, 401)
    """

    board_labels: np.ndarray
    board_reflectances: np.ndarray
    board_authored_rgb8: np.ndarray
    patch_names: tuple
    plate_labels: np.ndarray
    plate_reflectances: np.ndarray
    plate_authored_rgb8: np.ndarray
    wall_reflectance: np.ndarray


@dataclass(frozen=True, eq=False)
class LevelImages:
    """What one view shows for one source, profile and level (8-bit monitor sRGB).

    Attributes
    ----------
    level : int
    board : ndarray (H, W, 3) uint8
        The ColorChecker board as the headset shows it.
    plate : ndarray (S, S, 3) uint8
        The Ishihara plate as the headset shows it.
    wall_rgb8 : ndarray (3,) uint8
        The booth's grey walls as the headset shows them under the light.
    light_rgb8 : ndarray (3,) uint8
        The lamp: the level-1 light colour as the headset shows it.
    patch_rgb8 : ndarray (24, 3) uint8
        One value per ColorChecker patch (what ``board`` holds inside patch ``i``).
    texture_rgb8 : ndarray (24, 3) int
        The ColorChecker texels the engine is given at this level.
    engine_rgb8 : ndarray (24, 3) int
        What the engine outputs for them (DAC sent to the headset).
    """

    level: int
    board: np.ndarray
    plate: np.ndarray
    wall_rgb8: np.ndarray
    light_rgb8: np.ndarray
    patch_rgb8: np.ndarray
    texture_rgb8: np.ndarray
    engine_rgb8: np.ndarray


def _board_labels(patch_px: int = BOARD_PATCH_PX, gap_px: int = BOARD_GAP_PX) -> np.ndarray:
    """Patch index per texel of a 6 × 4 board, row 0 at the top (patch 1 top-left)."""
    pitch = patch_px + gap_px
    height, width = 4 * pitch + gap_px, 6 * pitch + gap_px
    labels = np.full((height, width), -1, dtype=np.int32)
    for index in range(24):
        row, column = divmod(index, 6)
        top, left = gap_px + row * pitch, gap_px + column * pitch
        labels[top:top + patch_px, left:left + patch_px] = index
    return labels


def board_patch_centre_uv(index: int, shape: tuple[int, int] | None = None) -> tuple[float, float]:
    """Texture coordinates (u right, v up, 0..1) of the centre of ColorChecker patch ``index`` (0-based)."""
    if not 0 <= index < 24:
        raise InputError(f"ColorChecker patch index {index} is outside 0..23")
    height, width = shape or _board_labels().shape
    pitch = BOARD_PATCH_PX + BOARD_GAP_PX
    row, column = divmod(index, 6)
    x = BOARD_GAP_PX + column * pitch + BOARD_PATCH_PX / 2
    y = BOARD_GAP_PX + row * pitch + BOARD_PATCH_PX / 2
    return x / width, 1.0 - y / height


@lru_cache(maxsize=1)
def scene_content() -> SceneContent:
    """The booth's surfaces: the ColorChecker and plate :data:`SCENE_PLATE_NUMBER` of the paper's set."""
    from workbench.ishihara.plates import (
        generate_plate,
        paper_coloured_plate,
        paper_plate_set_specs,
    )

    patches = colorchecker()
    # The plate exactly as generate_plate_set() makes it, without generating the other nine.
    spec = paper_plate_set_specs()[SCENE_PLATE_NUMBER - 1]
    plate = paper_coloured_plate(generate_plate(spec))
    plate_reflectances = np.vstack([plate.paper_reflectance[None, :], plate.dot_reflectances])
    wall = np.full((1, patches.reflectances.shape[1]), BOOTH_WALL_REFLECTANCE)
    return SceneContent(
        board_labels=_board_labels(),
        board_reflectances=patches.reflectances,
        board_authored_rgb8=np.asarray(COLORCHECKER_SRGB_REFERENCE),
        patch_names=tuple(patches.names),
        plate_labels=np.asarray(plate.labels, dtype=np.int32),
        plate_reflectances=plate_reflectances,
        plate_authored_rgb8=authored_srgb8(plate_reflectances),
        wall_reflectance=wall,
    )


def headset_to_monitor_rgb8(dac_rgb8, display: DisplayModel) -> np.ndarray:
    """The colour the headset emits for ``dac_rgb8``, as 8-bit sRGB on an ideal monitor.

    ``XYZ = display.forward(dac)``, scaled so the headset's white luminance is
    the monitor's, then the ideal sRGB display's inverse (clipped per channel
    where the monitor cannot show it).
    """
    monitor = SRGBDisplay()
    XYZ = display.forward(np.asarray(dac_rgb8, dtype=float))
    XYZ = XYZ * (monitor.white_XYZ[1] / float(display.white_XYZ[1]))
    return monitor.inverse_rgb8(XYZ).astype(np.uint8)


def _expand(labels: np.ndarray, colours: np.ndarray, offset: int, background) -> np.ndarray:
    table = np.vstack([np.asarray(background, dtype=np.uint8)[None, :], colours.astype(np.uint8)])
    return table[labels + offset]


def level_images(illuminant, display: DisplayModel, level: int, *, k: float = DEFAULT_K,
                 content: SceneContent | None = None) -> LevelImages:
    """What the view at ``level`` shows under ``illuminant`` on ``display`` (module doc).

    Parameters
    ----------
    illuminant : workbench.illuminants.Illuminant
    display : DisplayModel
        The headset (``workspace.profile.display_model()``).
    level : int
        1 or 2.
    """
    if level not in LEVELS:
        raise InputError(f"unknown colour-management level {level!r}; use 1 or 2")
    content = content or scene_content()
    sd = illuminant.sd
    light = light_colour(sd, display, k=k, observer=display.observer)
    if level == 1:
        board_texture = content.board_authored_rgb8
        plate_texture = content.plate_authored_rgb8
    else:
        board_texture = level2_texture(content.board_reflectances, sd, display, k=k,
                                       observer=display.observer).rgb8
        plate_texture = level2_texture(content.plate_reflectances, sd, display, k=k,
                                       observer=display.observer).rgb8
    wall_texture = authored_srgb8(content.wall_reflectance)
    if level == 2:
        wall_texture = level2_texture(content.wall_reflectance, sd, display, k=k,
                                      observer=display.observer).rgb8
    board_engine = engine_render(board_texture, light.rgb8)
    patches = headset_to_monitor_rgb8(board_engine, display)
    plate = headset_to_monitor_rgb8(engine_render(plate_texture, light.rgb8), display)
    wall = headset_to_monitor_rgb8(engine_render(wall_texture, light.rgb8), display)[0]
    lamp = headset_to_monitor_rgb8(light.rgb8[None, :], display)[0]
    return LevelImages(
        level=level,
        board=_expand(content.board_labels, patches, 1, (20, 20, 20)),
        plate=plate[content.plate_labels],
        wall_rgb8=wall, light_rgb8=lamp, patch_rgb8=patches,
        texture_rgb8=np.asarray(board_texture), engine_rgb8=board_engine,
    )
