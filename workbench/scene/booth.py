"""The virtual lightbooth as plain pyvista meshes: build once, re-light in place.

A grey box open at the front (floor, back wall, side walls, ceiling) with a
lamp under the ceiling, the ColorChecker board standing on the floor against
the back wall and the Ishihara plate beside it. :func:`build_booth` adds it to
one renderer of any :class:`pyvista.Plotter` (``off_screen=True`` for tests and
scripts, pyvistaqt's ``QtInteractor`` in the window); :func:`relight_booth`
writes new images into the existing textures' scalars and marks them
modified, so switching the source never rebuilds a mesh.

Shading. The board and the plate are drawn unlit (VTK lighting off, ambient 1,
diffuse 0, specular 0, white colour): a texel renders exactly its texture
value, which already *is* what the headset shows under the chosen source
(:mod:`workbench.scene.images`; the engine's light is in the texture, so a
second, VTK-side lighting would count it twice). The walls keep VTK's
Lambertian shading only so the box reads as a box; their base colour is the
grey wall as the headset shows it. Textures are sampled with nearest-texel
filtering and no mipmaps, so a patch's inside is exactly its value.

Scale: scene units are centimetres; the camera looks along −z into the booth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyvista as pv
from vtkmodules.util.numpy_support import vtk_to_numpy

from workbench.scene.images import LevelImages, board_patch_centre_uv

__all__ = [
    "BOOTH_SIZE_CM",
    "BOARD_WIDTH_CM",
    "PLATE_SIZE_CM",
    "BACKGROUND_RGB",
    "BoothHandles",
    "build_booth",
    "relight_booth",
    "board_patch_world_point",
    "booth_camera",
]

BOOTH_SIZE_CM = (80.0, 50.0, 50.0)
"""Inside width, height and depth of the booth."""

BOARD_WIDTH_CM = 34.0
"""Width of the ColorChecker board (its height follows the texture's aspect)."""

PLATE_SIZE_CM = 22.0
"""Side of the square Ishihara plate card."""

BACKGROUND_RGB = (0.16, 0.16, 0.17)
"""Outside the booth (a dark lab)."""

_BOARD_CENTRE_X = -14.0
_PLATE_CENTRE_X = 22.0
_FRONT_OFFSET_Z = 0.2  # how far in front of the back wall the board and plate stand


@dataclass
class BoothHandles:
    """What :func:`relight_booth` updates, and where the board is."""

    board_image: pv.ImageData
    plate_image: pv.ImageData
    wall_actors: tuple
    lamp_actor: object
    board_centre: tuple[float, float, float]
    board_size: tuple[float, float]


def _image_data(rgb: np.ndarray) -> pv.ImageData:
    """A VTK image holding ``rgb`` (rows top first) with VTK's bottom-up row order."""
    height, width, _ = rgb.shape
    image = pv.ImageData(dimensions=(width, height, 1))
    image.point_data["rgb"] = np.ascontiguousarray(rgb[::-1].reshape(-1, 3), dtype=np.uint8)
    image.point_data.active_scalars_name = "rgb"
    return image


def _write_image(image: pv.ImageData, rgb: np.ndarray) -> None:
    """Write ``rgb`` into ``image``'s scalars in place and mark them modified."""
    array = image.GetPointData().GetScalars()
    view = vtk_to_numpy(array)  # shares memory with the VTK array
    view[:] = rgb[::-1].reshape(-1, 3)
    array.Modified()
    image.Modified()


def _texture(image: pv.ImageData) -> pv.Texture:
    texture = pv.Texture(image)
    texture.interpolate = False
    texture.mipmap = False
    texture.SetColorModeToDirectScalars()
    return texture


def _unlit(actor) -> None:
    # A facing textured surface must render its texture value exactly: no
    # VTK lighting, ambient 1, diffuse 0, specular 0, white base colour.
    prop = actor.GetProperty()
    prop.SetLighting(False)
    prop.SetAmbient(1.0)
    prop.SetDiffuse(0.0)
    prop.SetSpecular(0.0)
    prop.SetAmbientColor(1.0, 1.0, 1.0)
    prop.SetColor(1.0, 1.0, 1.0)


def _textured_plane(plotter: pv.Plotter, centre, width: float, height: float,
                    image: pv.ImageData):
    plane = pv.Plane(center=centre, direction=(0.0, 0.0, 1.0), i_size=width, j_size=height,
                     i_resolution=1, j_resolution=1)
    # Texture coordinates u = 0..1 left to right, v = 0..1 bottom to top.
    points = np.asarray(plane.points)
    u = (points[:, 0] - (centre[0] - width / 2)) / width
    v = (points[:, 1] - (centre[1] - height / 2)) / height
    plane.active_texture_coordinates = np.column_stack([u, v]).astype(np.float32)
    actor = plotter.add_mesh(plane, texture=_texture(image), lighting=False,
                             show_scalar_bar=False, reset_camera=False)
    _unlit(actor)
    return actor


def build_booth(plotter: pv.Plotter, images: LevelImages) -> BoothHandles:
    """Add the booth, board, plate and lamp to ``plotter``'s active renderer, showing ``images``."""
    width, height, depth = BOOTH_SIZE_CM
    wall_colour = images.wall_rgb8 / 255.0
    walls = (
        pv.Plane(center=(0, 0, 0), direction=(0, 1, 0), i_size=depth, j_size=width),  # floor
        pv.Plane(center=(0, height, 0), direction=(0, -1, 0), i_size=depth, j_size=width),
        pv.Plane(center=(0, height / 2, -depth / 2), direction=(0, 0, 1), i_size=width,
                 j_size=height),  # back wall
        pv.Plane(center=(-width / 2, height / 2, 0), direction=(1, 0, 0), i_size=depth,
                 j_size=height),
        pv.Plane(center=(width / 2, height / 2, 0), direction=(-1, 0, 0), i_size=depth,
                 j_size=height),
    )
    wall_actors = tuple(plotter.add_mesh(wall, color=wall_colour, ambient=0.55, diffuse=0.45,
                                         specular=0.0, reset_camera=False) for wall in walls)
    lamp = pv.Box(bounds=(-width * 0.35, width * 0.35, height - 2.0, height - 0.5,
                          -depth * 0.35, depth * 0.05))
    lamp_actor = plotter.add_mesh(lamp, color=images.light_rgb8 / 255.0, lighting=False,
                                  reset_camera=False)
    _unlit(lamp_actor)
    lamp_actor.GetProperty().SetColor(*(images.light_rgb8 / 255.0))

    board_h_px, board_w_px = images.board.shape[:2]
    board_height = BOARD_WIDTH_CM * board_h_px / board_w_px
    board_centre = (_BOARD_CENTRE_X, 6.0 + board_height / 2, -depth / 2 + _FRONT_OFFSET_Z)
    board_image = _image_data(images.board)
    _textured_plane(plotter, board_centre, BOARD_WIDTH_CM, board_height, board_image)

    plate_centre = (_PLATE_CENTRE_X, 6.0 + PLATE_SIZE_CM / 2, -depth / 2 + _FRONT_OFFSET_Z)
    plate_image = _image_data(images.plate)
    _textured_plane(plotter, plate_centre, PLATE_SIZE_CM, PLATE_SIZE_CM, plate_image)

    plotter.set_background(BACKGROUND_RGB)
    booth_camera(plotter)
    return BoothHandles(board_image=board_image, plate_image=plate_image,
                        wall_actors=wall_actors, lamp_actor=lamp_actor,
                        board_centre=board_centre, board_size=(BOARD_WIDTH_CM, board_height))


def relight_booth(handles: BoothHandles, images: LevelImages) -> None:
    """Show ``images`` in an existing booth: textures written in place, colours set; nothing rebuilt."""
    _write_image(handles.board_image, images.board)
    _write_image(handles.plate_image, images.plate)
    for actor in handles.wall_actors:
        actor.GetProperty().SetColor(*(images.wall_rgb8 / 255.0))
    handles.lamp_actor.GetProperty().SetColor(*(images.light_rgb8 / 255.0))


def board_patch_world_point(handles: BoothHandles, index: int) -> tuple[float, float, float]:
    """World coordinates of the centre of ColorChecker patch ``index`` (0-based) on the board."""
    u, v = board_patch_centre_uv(index)
    cx, cy, cz = handles.board_centre
    width, height = handles.board_size
    return (cx - width / 2 + u * width, cy - height / 2 + v * height, cz)


def booth_camera(plotter: pv.Plotter, aspect: float | None = None) -> None:
    """Look into the booth from the front, the whole opening in view of a viewport ``aspect`` (w/h) wide."""
    width, height, depth = BOOTH_SIZE_CM
    view_angle = 40.0
    half = np.tan(np.radians(view_angle / 2))
    distance = depth * 1.75
    if aspect:  # far enough back that the opening's width fits too
        distance = max(distance, depth / 2 + 0.9 * (width / 2) / (half * aspect))
    plotter.camera_position = [(0.0, height * 0.5, distance),
                               (0.0, height * 0.45, -depth / 2), (0.0, 1.0, 0.0)]
    plotter.camera.view_angle = view_angle
