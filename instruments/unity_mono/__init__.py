"""The Unity package's patch-server core (C#), compiled with ``mcs`` and run under ``mono``.

The C# files of the Unity package that do not draw
(``workbench/export/runtime/unity/Runtime/Patch/``) run here unchanged, in two console programs
of this folder: ``PatchServerHost.cs`` (the patch server with a headless presenter, started by
``python -m instruments.patch_server --impl unity-mono``) and ``PatchColourCheck.cs`` (the
patch shader's colour-space arithmetic checked for every DAC). :func:`build_program` compiles
them on demand into a cache directory outside the source tree.
"""

from instruments.unity_mono.build import (
    PROGRAMS,
    MonoUnavailable,
    build_program,
    mono_command,
    patch_core_sources,
)

__all__ = ["PROGRAMS", "MonoUnavailable", "build_program", "mono_command", "patch_core_sources"]
