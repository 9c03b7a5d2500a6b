"""The runtime bundle as the WebXR page reads it: which files it may fetch, and the lightbooth it shows.

The page fetches the bundle's own files (``lights.json``, ``display_inverse.json``,
the drive-correction table, and ``level2/lightbooth/``'s coefficients, light
records and ``preview.png``) and re-authors the level-2 texture on the GPU as
``runtime/level2_relight.frag`` does. :class:`SceneBundle` checks on opening
that the bundle has what the page needs, with one message naming the fix, and
serves nothing else (:meth:`SceneBundle.file`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from workbench.errors import InputError
from workbench.vr.scene_cubes import SCENE_CUBE, atlas_layout

__all__ = ["SUPPORTED_BUNDLE_VERSION", "SceneBundle", "scene_cube_hint"]

SUPPORTED_BUNDLE_VERSION = 1
"""Newest ``bundle.json`` ``format_version`` the page reads."""

_TOP_FILES = ("bundle.json", "lights.json", "display_inverse.json", "display_drive_correction.bin")
_CUBE_FILES = ("coefficients.json", "coefficients.bin", "lights.json", "preview.png")
_MAX_JSON_BYTES = 64 * 1024 * 1024


def scene_cube_hint(folder) -> str:
    """The two commands that make a bundle the page can show."""
    return (f"make one: python -m workbench vr bundle PROFILE --bundle {folder} (or vr cube --out CUBES, "
            f"then export PROFILE --bundle {folder} --cube CUBES/{SCENE_CUBE}.npz)")


def _json(path: Path, folder: Path) -> dict:
    if not path.is_file():
        raise InputError(f"--bundle {folder}: {path.relative_to(folder)} is missing; it is not a complete "
                         f"runtime bundle ({scene_cube_hint(folder)})")
    if path.stat().st_size > _MAX_JSON_BYTES:
        raise InputError(f"--bundle {folder}: {path.name} is larger than {_MAX_JSON_BYTES} bytes; not a bundle file")
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"--bundle {folder}: {path.relative_to(folder)} is not valid JSON ({error}); "
                         "export the bundle again") from None
    if not isinstance(document, dict):
        raise InputError(f"--bundle {folder}: {path.relative_to(folder)} is not a JSON object; export it again")
    return document


@dataclass(frozen=True)
class SceneBundle:
    """A runtime bundle holding the lightbooth cube (module doc).

    Attributes
    ----------
    folder : Path
    device : str
        The headset the bundle is for.
    lights : tuple of dict
        ``{"id", "name", "rgb8"}`` per light, in the bundle's order.
    cube : dict
        The manifest's entry of the lightbooth cube (width, height, channels, layers, ...).
    atlas : dict
        Where the board, plate and wall lie in the cube (:func:`~workbench.vr.scene_cubes.atlas_layout`).
    """

    folder: Path
    device: str
    lights: tuple
    cube: dict
    atlas: dict

    @classmethod
    def open(cls, folder) -> "SceneBundle":
        """Read and check ``folder``.

        Raises
        ------
        InputError
            Not a bundle, a newer format, no lightbooth cube, or one of another layout.
        """
        folder = Path(folder)
        if not folder.is_dir():
            raise InputError(f"--bundle {folder}: no such folder; {scene_cube_hint(folder)}")
        manifest = _json(folder / "bundle.json", folder)
        if manifest.get("format") != "vr-colour-workbench-bundle":
            raise InputError(f"--bundle {folder}: bundle.json is not a VR colour workbench bundle; "
                             f"{scene_cube_hint(folder)}")
        version = manifest.get("format_version")
        if not isinstance(version, int) or isinstance(version, bool) or version > SUPPORTED_BUNDLE_VERSION:
            raise InputError(f"--bundle {folder}: bundle format_version {version!r} is not one this page "
                             f"reads (up to {SUPPORTED_BUNDLE_VERSION}); update the workbench")
        cubes = [c for c in manifest.get("cubes") or [] if isinstance(c, dict)]
        cube = next((c for c in cubes if c.get("name") == SCENE_CUBE), None)
        if cube is None:
            names = ", ".join(str(c.get("name")) for c in cubes) or "none"
            raise InputError(f"--bundle {folder} has no level-2 '{SCENE_CUBE}' cube (it has {names}); "
                             f"{scene_cube_hint(folder)}")
        atlas = atlas_layout()
        if [cube.get("width"), cube.get("height")] != atlas["size"]:
            raise InputError(f"--bundle {folder}: its '{SCENE_CUBE}' cube is {cube.get('width')} × "
                             f"{cube.get('height')} texels, not the {atlas['size'][0]} × {atlas['size'][1]} "
                             f"lightbooth this workbench writes; {scene_cube_hint(folder)}")
        table = _json(folder / "lights.json", folder)
        lights = []
        for entry in table.get("lights") or []:
            if isinstance(entry, dict) and isinstance(entry.get("id"), str):
                lights.append({"id": entry["id"], "name": str(entry.get("name", entry["id"])),
                               "rgb8": entry.get("rgb8")})
        if not lights:
            raise InputError(f"--bundle {folder}: lights.json lists no lights; export the bundle again")
        for name in _CUBE_FILES:
            if not (folder / "level2" / SCENE_CUBE / name).is_file():
                raise InputError(f"--bundle {folder}: level2/{SCENE_CUBE}/{name} is missing; export the "
                                 "bundle again")
        return cls(folder=folder, device=str(manifest.get("device", "")), lights=tuple(lights),
                   cube=cube, atlas=atlas)

    def light_ids(self) -> tuple:
        """The bundle's light ids, in its order."""
        return tuple(light["id"] for light in self.lights)

    def file(self, relative: str) -> Path | None:
        """The bundle file the page asked for, or ``None`` when it is not one the page may read."""
        allowed = set(_TOP_FILES) | {f"level2/{SCENE_CUBE}/{name}" for name in _CUBE_FILES}
        if relative not in allowed:
            return None
        path = self.folder / relative
        return path if path.is_file() else None

    def describe(self) -> dict:
        """What the page needs to know before fetching the files."""
        return {"folder": str(self.folder), "device": self.device, "lights": list(self.lights),
                "cube": SCENE_CUBE, "width": self.cube.get("width"), "height": self.cube.get("height"),
                "atlas": self.atlas}
