"""The runtime bundle: what a VR application loads to reproduce the workbench's colours.

- :mod:`.bundle`: :func:`write_bundle`, the folder and its manifest.
- :mod:`.cube_lut`: ``display_inverse.cube`` (engine sRGB output → HMD DAC/255) and its
  accuracy against the exact inverse.
- :mod:`.runtime_inverse`: the display inverse as a shader evaluates it.
- :mod:`.lights_table`: ``lights.json``, level 1.
- :mod:`.level2_files`: level-2 coefficient textures, basis, per-light matrices; K chosen
  for texel-exact runtime output.
- ``runtime/``: package data copied into every bundle: ``reference_consumer.py`` (numpy +
  json only), ``level2_relight.frag``/``.vert`` (GLSL 4.30), the bundle README template and
  ``unity/``, the Unity package (loader ``VrColourBundle.cs``, components, the patch server,
  shaders incl. ``Level2Relight.hlsl``, the Lightbooth sample), copied whole as ``runtime/unity/``.
"""

from __future__ import annotations

from workbench.export.bundle import (
    BUNDLE_FORMAT,
    BUNDLE_FORMAT_VERSION,
    RUNTIME_FILES,
    BundleSummary,
    runtime_file,
    write_bundle,
)
from workbench.export.cube_lut import (
    DEFAULT_LUT_SIZE,
    CubeAccuracy,
    cube_accuracy,
    display_inverse_table,
    read_cube_file,
    srgb_input_to_XYZ,
    white_mapping_XYZ,
    write_cube_file,
)
from workbench.export.level2_files import (
    ComponentChoice,
    choose_cube_basis,
    encode_channels,
    level2_light,
    runtime_level2_texels,
)
from workbench.export.lights_table import lights_table
from workbench.export.runtime_inverse import (
    InverseAccuracy,
    RuntimeDisplayInverse,
    runtime_display_inverse,
    runtime_inverse_accuracy,
)

__all__ = [
    "BUNDLE_FORMAT",
    "BUNDLE_FORMAT_VERSION",
    "DEFAULT_LUT_SIZE",
    "RUNTIME_FILES",
    "BundleSummary",
    "ComponentChoice",
    "CubeAccuracy",
    "InverseAccuracy",
    "RuntimeDisplayInverse",
    "choose_cube_basis",
    "cube_accuracy",
    "display_inverse_table",
    "encode_channels",
    "level2_light",
    "lights_table",
    "read_cube_file",
    "runtime_display_inverse",
    "runtime_inverse_accuracy",
    "runtime_file",
    "runtime_level2_texels",
    "srgb_input_to_XYZ",
    "white_mapping_XYZ",
    "write_bundle",
    "write_cube_file",
]
