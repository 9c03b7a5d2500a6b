"""Compile the Unity package's patch core and a console ``Main`` with ``mcs``, cached by content.

The executables go to ``platformdirs.user_cache_dir("vr-workbench")/unity-mono/<hash>/``, where
the hash covers the program's name, every source file's name and bytes, the compiler and its
flags: an edited source is compiled again, an unchanged one is not. A build is written to a
temporary name and renamed, so that two processes building at once both end with a whole file.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import platformdirs

__all__ = ["PROGRAMS", "MonoUnavailable", "build_program", "mono_command", "patch_core_sources",
           "MCS_FLAGS", "INSTALL_HINT"]

_HERE = Path(__file__).resolve().parent
PATCH_CORE_DIR = _HERE.parents[1] / "workbench" / "export" / "runtime" / "unity" / "Runtime" / "Patch"
"""The Unity package's protocol core: plain C#, no UnityEngine."""

MCS_FLAGS = ("-langversion:7.2", "-warnaserror+", "-target:exe", "-nologo")
"""C# 7.2 as Unity 2021.3 accepts it, warnings as errors, as the Unity compile tests use."""

INSTALL_HINT = "install them with `sudo apt-get install mono-mcs mono-runtime` (make test installs them as root)"

PROGRAMS = {
    "patch-server": ("PatchServerHost.cs", ("PatchJson.cs", "PatchProtocol.cs", "PatchServerCore.cs", "PatchColour.cs")),
    "colour-check": ("PatchColourCheck.cs", ("PatchColour.cs",)),
}
"""Program name → (its ``Main`` in this folder, the core files it is compiled with)."""

_COMPILE_TIMEOUT_S = 180.0


class MonoUnavailable(RuntimeError):
    """``mono`` or ``mcs`` is not installed, or the C# sources are not where they belong."""


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise MonoUnavailable(f"{name} not found: the Unity patch core runs under mono; {INSTALL_HINT}")
    return path


def patch_core_sources() -> list[Path]:
    """The ``.cs`` files of the Unity package's protocol core, sorted."""
    sources = sorted(PATCH_CORE_DIR.glob("*.cs"))
    if not sources:
        raise MonoUnavailable(f"the Unity package's patch core is missing: no .cs files in {PATCH_CORE_DIR}")
    return sources


def build_program(name: str) -> Path:
    """The compiled ``.exe`` of program ``name`` (see :data:`PROGRAMS`), built if not cached.

    Raises
    ------
    MonoUnavailable
        When ``mcs`` is missing, or the compilation fails (the message holds the compiler's output).
    """
    if name not in PROGRAMS:
        raise ValueError(f"unknown program {name!r}; use one of {', '.join(PROGRAMS)}")
    mcs = _tool("mcs")
    main, core = PROGRAMS[name]
    sources = [_HERE / main] + [PATCH_CORE_DIR / file for file in core]
    missing = [str(path) for path in sources if not path.is_file()]
    if missing:
        raise MonoUnavailable(f"C# sources missing: {', '.join(missing)}")
    digest = hashlib.sha256()
    for part in (name, mcs, *MCS_FLAGS):
        digest.update(part.encode() + b"\0")
    for path in sources:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    folder = Path(platformdirs.user_cache_dir("vr-workbench")) / "unity-mono" / digest.hexdigest()[:20]
    target = folder / f"{name}.exe"
    if target.is_file():
        return target
    folder.mkdir(parents=True, exist_ok=True)
    handle, partial = tempfile.mkstemp(prefix=f".{name}-", suffix=".exe", dir=folder)
    os.close(handle)
    try:
        result = subprocess.run([mcs, *MCS_FLAGS, f"-out:{partial}", *map(str, sources)],
                                capture_output=True, text=True, timeout=_COMPILE_TIMEOUT_S)
        if result.returncode != 0:
            raise MonoUnavailable(f"mcs could not compile {name}: {(result.stdout + result.stderr).strip()}")
        os.replace(partial, target)
    finally:
        if os.path.exists(partial):
            os.unlink(partial)
    return target


def mono_command(name: str) -> list[str]:
    """``[mono, path/to/name.exe]``: the command line that runs program ``name``, built if needed."""
    mono = _tool("mono")
    return [mono, "--debug", str(build_program(name))]
