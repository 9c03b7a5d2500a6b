"""The runtime bundle: everything a VR application loads to show the workbench's colours.

:func:`write_bundle` writes, into one folder (built beside it and swapped in
whole, so a reader never sees half a bundle):

==============================  ==============================================================
``bundle.json``                 manifest: format and version, the files, lights, cubes, and the
                                runtime colour space the data assume
``profile.vrprofile.json``      the profile, with its ``lut3d`` and ``runtime`` blocks filled in
``display_inverse.cube``        engine sRGB-encoded output → HMD DAC/255 (:mod:`.cube_lut`)
``display_inverse.json``        the inverse in the level-2 runtime's form (:mod:`.runtime_inverse`),
                                plus ``display_drive_correction.bin`` where the model needs it
``lights.json``                 the level-1 light table (:mod:`.lights_table`)
``level2/<cube>/``              coefficients, basis, per-light matrices and tables (:mod:`.level2_files`)
``runtime/``                    ``reference_consumer.py`` (numpy + json only) and the GLSL shaders
``runtime/unity/``              the Unity package (Package Manager layout: ``package.json``,
                                ``Runtime/`` with the C# loader, its components and the HLSL
                                shaders, ``Samples~/Lightbooth``), copied whole so that Unity's
                                "Add package from disk" works on the bundle as written
``README.md``                   how a runtime uses each file, and the three lines that load it in Unity
==============================  ==============================================================
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import string
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from workbench.errors import InputError
from workbench.export.cube_lut import (
    DEFAULT_LUT_SIZE,
    CubeAccuracy,
    cube_accuracy,
    display_inverse_table,
    white_mapping_XYZ,
    write_cube_file,
)
from workbench.export.level2_files import (
    DEFAULT_IDENTICAL_SHARE,
    choose_cube_basis,
    level2_light,
    write_json,
    write_level2_cube,
)
from workbench.export.lights_table import lights_table
from workbench.export.runtime_inverse import (
    CELLS,
    InverseAccuracy,
    runtime_display_inverse,
    runtime_inverse_accuracy,
)
from workbench.fileio import _umask, atomic_writer
from workbench.profile import PROFILE_FORMAT_VERSION, RUNTIME_COLOUR_SPACE, Profile, save_profile

__all__ = [
    "BUNDLE_FORMAT",
    "BUNDLE_FORMAT_VERSION",
    "RUNTIME_FILES",
    "UNITY_PACKAGE",
    "BundleSummary",
    "write_bundle",
    "runtime_file",
    "unity_package_files",
    "LIGHTBOOTH_CUBES",
    "lightbooth_cubes",
    "write_lightbooth_cubes",
]

BUNDLE_FORMAT = "vr-colour-workbench-bundle"
BUNDLE_FORMAT_VERSION = 1

RUNTIME_FILES = ("reference_consumer.py", "level2_relight.frag", "level2_relight.vert")
"""Files of ``workbench/export/runtime/`` copied into every bundle's ``runtime/``."""

UNITY_PACKAGE = "unity"
"""Folder of ``workbench/export/runtime/`` holding the Unity package, copied whole into every
bundle as ``runtime/unity/`` (:func:`unity_package_files`)."""

_NOT_PACKAGE = shutil.ignore_patterns("__pycache__", "*.pyc", ".DS_Store")

_NAME = re.compile(r"[^A-Za-z0-9_-]+")

LIGHTBOOTH_CUBES = ("colorchecker", "ishihara")
"""Level-2 cubes the Unity package's Lightbooth sample shows (:func:`lightbooth_cubes`)."""

BOARD_FRAME_REFLECTANCE = 0.02
"""Flat reflectance of the ColorChecker board's black frame in :func:`lightbooth_cubes`."""


def runtime_file(name: str) -> Path:
    """Path of a shipped runtime file (package data of ``workbench.export``).

    ``name`` is relative to ``workbench/export/runtime/``, ``/``-separated: e.g.
    ``"reference_consumer.py"`` or ``"unity/Runtime/VrColourBundle.cs"``.
    """
    path = Path(str(resources.files("workbench.export").joinpath("runtime", *name.split("/"))))
    if not path.is_file():
        raise FileNotFoundError(f"runtime file {name!r} is missing from the installation")
    return path


def _unity_package() -> Path:
    path = Path(str(resources.files("workbench.export").joinpath("runtime", UNITY_PACKAGE)))
    if not (path / "package.json").is_file():
        raise FileNotFoundError("the Unity package (runtime/unity/package.json) is missing from "
                                "the installation")
    return path


def unity_package_files() -> tuple[str, ...]:
    """The Unity package's files, ``/``-separated and relative to the package folder, sorted."""
    root = _unity_package()
    return tuple(sorted(path.relative_to(root).as_posix() for path in root.rglob("*")
                        if path.is_file() and "__pycache__" not in path.parts
                        and path.suffix != ".pyc" and path.name != ".DS_Store"))


def lightbooth_cubes() -> list:
    """The Lightbooth sample's cubes as ``(name, ReflectanceCube)``, for ``write_bundle(cubes=...)``.

    The workbench's own booth surfaces (:func:`workbench.scene.images.scene_content`): the
    ColorChecker board (24 patches in their label layout, the frame a flat
    :data:`BOARD_FRAME_REFLECTANCE`) and Ishihara plate 3 of the paper's set, sampled at the
    paper's 101 bands (380–780 nm, 4 nm: every fourth of the working 1 nm bands).
    """
    from workbench.colorimetry import WORKING_WAVELENGTHS
    from workbench.hyperspectral import PAPER_CUBE_WAVELENGTHS, ReflectanceCube
    from workbench.scene.images import scene_content

    bands = np.searchsorted(WORKING_WAVELENGTHS, PAPER_CUBE_WAVELENGTHS)
    assert np.array_equal(WORKING_WAVELENGTHS[bands], PAPER_CUBE_WAVELENGTHS)
    content = scene_content()
    board = np.vstack([np.full((1, len(WORKING_WAVELENGTHS)), BOARD_FRAME_REFLECTANCE),
                       content.board_reflectances])[:, bands]
    plate = content.plate_reflectances[:, bands]
    return [("colorchecker", ReflectanceCube(board[content.board_labels + 1].astype(np.float32),
                                             PAPER_CUBE_WAVELENGTHS, "ColorChecker board (scene)")),
            ("ishihara", ReflectanceCube(plate[content.plate_labels].astype(np.float32),
                                         PAPER_CUBE_WAVELENGTHS, "Ishihara plate 3 (scene)"))]


def write_lightbooth_cubes(folder) -> list[Path]:
    """Write :func:`lightbooth_cubes` as ``colorchecker.npz`` and ``ishihara.npz`` in ``folder``
    (for ``export --cube``; the file names give the cube names)."""
    from workbench.hyperspectral import write_cube

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [write_cube(cube, folder / f"{name}.npz") for name, cube in lightbooth_cubes()]


@dataclass(frozen=True)
class BundleSummary:
    """What :func:`write_bundle` wrote and the figures it measured."""

    directory: Path
    lights: tuple[str, ...]
    cube_accuracy: CubeAccuracy
    cubes: tuple[dict, ...]
    drive_correction: bool
    inverse_accuracy: InverseAccuracy

    def to_json(self) -> dict:
        return {"bundle": str(self.directory), "lights": list(self.lights),
                "display_inverse_cube": {"size": self.cube_accuracy.size,
                                         **self.cube_accuracy.to_json()},
                "drive_correction": self.drive_correction,
                "runtime_inverse": self.inverse_accuracy.to_json(), "cubes": list(self.cubes)}


def _cube_name(path: Path, taken: set[str]) -> str:
    name = _NAME.sub("-", path.name.split(".")[0]).strip("-") or "cube"
    if name in taken:
        raise InputError(f"--cube {path}: two cubes would both be named {name!r} in the bundle; "
                         "rename one file")
    return name


@contextlib.contextmanager
def _staged_directory(target: Path):
    """A fresh folder beside ``target`` that replaces it when the block succeeds."""
    if target.exists() and not target.is_dir():
        raise InputError(f"--bundle {target}: exists and is not a folder")
    if target.is_dir() and any(target.iterdir()) and not (target / "bundle.json").is_file():
        raise InputError(f"--bundle {target}: the folder holds files and is not a bundle; "
                         "give a new or empty folder (an existing bundle is replaced)")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.",
                                        suffix=".partial"))
    except OSError as error:
        raise InputError(f"--bundle {target}: cannot create a folder in {target.parent} "
                         f"({error.strerror or error}); give a writable folder") from None
    os.chmod(staging, 0o777 & ~_umask())  # a folder as mkdir makes it, not mkdtemp's 0700
    try:
        yield staging
        old = None
        if target.exists():
            # beside the staging folder under its unique name: a leftover of a killed export
            # (whose pid may come back) cannot block this one
            old = staging.with_name(staging.name.removesuffix(".partial") + ".old")
            os.replace(target, old)
        try:
            os.replace(staging, target)
        except OSError:
            if old is not None:
                os.replace(old, target)  # the earlier bundle stays, whole
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _readme(profile: Profile, manifest: dict, accuracy: CubeAccuracy) -> str:
    template = string.Template(runtime_file("README.md.template").read_text(encoding="utf-8"))
    cubes = manifest["cubes"]
    cube_lines = "\n".join(
        f"- `level2/{c['name']}/`: {c['width']} × {c['height']} texels (width × height), "
        f"K = {c['components']} "
        f"basis coefficients + {c['split']} precision channel(s) = {c['channels']} channels in "
        f"{c['layers']} RGBA16F layer(s)" for c in cubes) or "- (none: export with --cube CUBE)"
    example_cube = cubes[0]["name"] if cubes else "CUBE"
    return template.substitute(
        device=profile.device.get("name", "display"), model=manifest["display_model"],
        lights=", ".join(f"`{light}`" for light in manifest["lights"]),
        first_light=manifest["lights"][0], example_cube=example_cube, cubes=cube_lines,
        size=accuracy.size, mean=f"{accuracy.mean_dE00:.3f}", p95=f"{accuracy.p95_dE00:.3f}",
        max=f"{accuracy.max_dE00:.3f}", samples=accuracy.samples,
        white=", ".join(f"{v:.4g}" for v in manifest["white_mapping_XYZ"]),
        k=f"{profile.k:g}", colour_space=RUNTIME_COLOUR_SPACE,
        correction=("This model's drive is not affine in XYZ: the correction table is "
                    "display_drive_correction.bin" if manifest["drive_correction"]
                    else "This model's drive is affine in XYZ: no correction table"),
        inverse_identical=f"{100 * manifest['runtime_inverse']['identical_share']:.2f}",
        inverse_max=manifest["runtime_inverse"]["max_counts"],
        apl=_apl_text(manifest["apl"], manifest.get("apl_test")), cells=CELLS,
        cells_last=CELLS - 1,
        version=BUNDLE_FORMAT_VERSION)


def _apl_text(block: dict | None, test: dict | None = None) -> str:
    """The bundle README's account of the APL curve (or of its absence, tested or not)."""
    if block is None and test is not None and not test["found"]:
        return ("This profile holds no APL curve (`apl` is null in `bundle.json`) because its "
                "diagnosis tested `apl-dependence` on patches shown as windows on surrounds and "
                "did not find it (`apl_test` in `bundle.json` and the profile: "
                f"{test['evidence']}): every table of this bundle holds on any frame, "
                "whatever its load; a runtime needs no load compensation.")
    if block is None:
        return ("This profile holds no APL curve (`apl` is null in `bundle.json`): its diagnosis "
                "found no `apl-dependence`, or its calibration showed every patch full field, "
                "so nothing says how the display changes with the frame's load.")
    shares = ", ".join(f"{v:.3g}" for v in block["power_shares"])
    transfer = block["transfer"]
    lin = ("(DAC/255)^γ_c with γ = " + ", ".join(f"{g:.3g}" for g in transfer["gammas"])
           if transfer["method"] == "power" else
           f"ST 2084 (PQ) of DAC/255 over {transfer['peak_cd_m2']:g} cd/m²")
    held = "; ".join(f"leave one {h['by']} out: {h['luminance_error_pct']:.1f} % of luminance, "
                     f"{h['mean_dE00']:.2f} ΔE00" for h in block.get("held_out", []))
    return (f"`bundle.json` `apl` (also in the profile) is this display's APL curve: a frame of "
            f"load L shows gain(L) = (1 + (L/{block['knee']:.4g})^{block['sharpness']:.4g})"
            f"^(−{block['exponent']:.4g}/{block['sharpness']:.4g}) of what it shows at load 0. "
            f"The load is L = Σ_c s_c · mean over the frame's pixels of lin_c(DAC_c), with "
            f"lin_c = {lin} and power shares s = ({shares}) (0 = black, 1 = full-field white). "
            "Every table of this bundle holds at the reference load: each colour shown full "
            "field (its own L_ref = Σ_c s_c lin_c(DAC_c)). A runtime compensates a frame of "
            "load L by scaling a colour's linear output by gain(L_ref)/gain(L) (as far as the "
            "drive has headroom; a pixel at DAC 255 cannot be raised)."
            + (f" Held out: {held}." if held else ""))


def write_bundle(profile: Profile, directory, *, light_ids: Sequence[str] | None = None,
                 cubes: Sequence = (), lut_size: int = DEFAULT_LUT_SIZE,
                 target_share: float = DEFAULT_IDENTICAL_SHARE) -> BundleSummary:
    """Write the runtime bundle of ``profile`` into ``directory`` (module doc).

    Parameters
    ----------
    profile : Profile
    directory : path-like
        New, empty, or an earlier bundle (replaced whole).
    light_ids : sequence of str, optional
        Library source ids; default: the profile's own lights.
    cubes : sequence of path-like or (name, ReflectanceCube)
        Hyperspectral cubes to export for level 2.
    lut_size : int
        Nodes per axis of ``display_inverse.cube``.
    target_share : float
        Share of held-out texels whose runtime texel must equal the full-band
        level-2 texel when K is chosen (:func:`~.level2_files.choose_cube_basis`).
    """
    from workbench.hyperspectral import ReflectanceCube, read_cube
    from workbench.illuminants import get_illuminant

    directory = Path(directory)
    light_ids = tuple(light_ids) if light_ids else tuple(light["id"] for light in profile.lights)
    if not light_ids:
        raise InputError("the profile has no lights; name some with --lights ID,...")
    illuminants = [get_illuminant(light_id) for light_id in light_ids]
    light_ids = tuple(illuminant.id for illuminant in illuminants)
    twice = sorted({light_id for light_id in light_ids if light_ids.count(light_id) > 1})
    if twice:
        raise InputError(f"light {', '.join(twice)} named more than once (--lights, or the "
                         "profile's lights); a bundle holds each light once")
    display = profile.display_model()
    loaded, taken = [], set()
    for item in cubes:
        if isinstance(item, tuple):
            name, cube = item
            if not isinstance(cube, ReflectanceCube) or _NAME.search(name) or not name:
                raise InputError(f"cube {name!r}: give (name, ReflectanceCube) with a name of "
                                 "letters, digits, '-' and '_'")
            if name in taken:
                raise InputError(f"two cubes named {name!r}")
        else:
            name, cube = _cube_name(Path(item), taken), read_cube(item)
        taken.add(name)
        loaded.append((name, cube))

    table = display_inverse_table(display, profile.k, lut_size)   # checks lut_size first
    inverse = runtime_display_inverse(display)
    inverse_accuracy = runtime_inverse_accuracy(inverse, display)
    accuracy = cube_accuracy(table, display, profile.k)
    white = white_mapping_XYZ(display, profile.k)
    lut3d = {"file": "display_inverse.cube", "size": lut_size, "direction": "sRGB_to_DAC",
             "input": "engine output, sRGB-encoded (IEC 61966-2-1) on 0..1, as colours of the "
                      "ideal sRGB display",
             "output": "HMD DAC / 255 from the profile's display inverse (out of gamut: clipped "
                       "per channel in linear drive)",
             "white_mapping": {"input_rgb": [1.0, 1.0, 1.0], "XYZ": [float(v) for v in white],
                               "description": "sRGB white is CIE D65 at Y = k * Y_white of the "
                                              "headset (relative colorimetry, design §2)"},
             "convention": "Iridas/Resolve .cube: LUT_3D_SIZE, no DOMAIN_ lines (0..1), red "
                           "fastest; read by Unity HDRP and DaVinci Resolve",
             "accuracy": accuracy.to_json()}
    runtime = {"colour_space": RUNTIME_COLOUR_SPACE,
               "framebuffer": "8-bit, sRGB-encoded by the engine (linear workflow); the HMD "
                              "receives these values as DAC",
               "notes": "Level 1: set the light colour to lights.json rgb8. Level 2: relight the "
                        "level2/ textures with the shader. Other sRGB content: apply "
                        "display_inverse.cube as the last colour step; never apply it to "
                        "level-1/level-2 output, which is already in DAC."}
    bundle_profile = replace(profile.with_lights(light_ids), lut3d=lut3d, runtime=runtime)

    level2 = []
    with _staged_directory(directory) as staging:
        save_profile(bundle_profile, staging / "profile.vrprofile.json")
        write_cube_file(staging / "display_inverse.cube", table,
                        title=f"{profile.device.get('name', 'display')}: sRGB to HMD DAC",
                        comments=[f"in: engine output, sRGB-encoded 0..1; sRGB white = D65 at "
                                  f"Y = k*Y_white = {white[1]:.6g} ({profile.xyz_scale})",
                                  "out: HMD DAC/255 from the display inverse "
                                  f"({display.describe()})",
                                  "red fastest; trilinear vs exact inverse, in gamut: mean "
                                  f"dE00 {accuracy.mean_dE00:.4f}, p95 {accuracy.p95_dE00:.4f}, "
                                  f"max {accuracy.max_dE00:.4f}"])
        write_json(staging / "display_inverse.json",
                    {**inverse.to_json(), "accuracy": inverse_accuracy.to_json()})
        if inverse.correction is not None:
            with atomic_writer(staging / "display_drive_correction.bin", "wb") as handle:
                handle.write(np.ascontiguousarray(inverse.correction, dtype="<f4").tobytes())
        write_json(staging / "lights.json", lights_table(bundle_profile, light_ids))
        for name, cube in loaded:
            basis, choice = choose_cube_basis(cube, display, illuminants, inverse, k=profile.k,
                                              observer=profile.observer,
                                              target_share=target_share)
            records = [level2_light(basis, illuminant, display, inverse, k=profile.k,
                                    split=choice.split) for illuminant in illuminants]
            level2.append(write_level2_cube(staging, name, cube, basis, choice.split, records,
                                            choice))
        (staging / "runtime").mkdir()
        for name in RUNTIME_FILES:
            shutil.copyfile(runtime_file(name), staging / "runtime" / name)
        shutil.copytree(_unity_package(), staging / "runtime" / UNITY_PACKAGE,
                        ignore=_NOT_PACKAGE, copy_function=shutil.copyfile)
        manifest = {"format": BUNDLE_FORMAT, "format_version": BUNDLE_FORMAT_VERSION,
                    "profile": "profile.vrprofile.json",
                    "profile_format_version": PROFILE_FORMAT_VERSION,
                    "device": profile.device.get("name", ""), "display_model": display.describe(),
                    "runtime_colour_space": RUNTIME_COLOUR_SPACE,
                    "display_inverse_cube": "display_inverse.cube",
                    "display_inverse": "display_inverse.json",
                    "drive_correction": inverse.correction is not None,
                    "runtime_inverse": inverse_accuracy.to_json(),
                    "white_mapping_XYZ": [float(v) for v in white],
                    "lights_file": "lights.json", "lights": list(light_ids),
                    "cubes": level2, "apl": profile.apl, "apl_test": profile.apl_test}
        with atomic_writer(staging / "README.md") as handle:
            handle.write(_readme(bundle_profile, manifest, accuracy))
        write_json(staging / "bundle.json", manifest)
    return BundleSummary(directory=directory, lights=light_ids, cube_accuracy=accuracy,
                         cubes=tuple(level2), drive_correction=inverse.correction is not None,
                         inverse_accuracy=inverse_accuracy)
