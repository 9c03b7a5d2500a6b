"""Atomic file output: write into a hidden staging folder beside the targets, fsync, rename.

A writer that fails half-way leaves the previous files (if any) intact and no
partial file behind; a reader never sees a half-written cube or texture. The
staged files carry the targets' own names (so libraries that derive one file's
name from another's, such as ENVI's header → data, or that append a suffix,
write exactly what will be renamed). For formats made of several files the
renames happen in the order given — pass the header last, so that a header
always points at complete data.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["atomic_output"]


def _fsync_path(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # some file systems cannot sync a directory; the rename is still atomic
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_output(*targets):
    """Staged paths for ``targets`` (all in one folder); on success they replace the targets.

    Parameters
    ----------
    *targets : path-like
        Final file paths, all in the same directory.

    Yields
    ------
    list of Path
        Where to write each file; same names as the targets, in a hidden
        staging folder of the targets' directory (same file system, so the
        final rename is atomic).

    Examples
    --------
    >>> with atomic_output("cube.img", "cube.hdr") as (data, header):  # doctest: +SKIP
    ...     data.write_bytes(b"...")
    ...     header.write_text("ENVI ...")
    """
    targets = [Path(t) for t in targets]
    directories = {target.parent.resolve() for target in targets}
    if len(directories) != 1:
        raise ValueError(f"atomic_output needs targets in one directory, got {sorted(directories)}")
    directory = targets[0].parent
    directory.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=directory, prefix=f".{targets[0].name}.", suffix=".partial"))
    try:
        staged = [staging / target.name for target in targets]
        yield staged
        for path in staged:
            if not path.exists():
                raise FileNotFoundError(f"the writer produced no {path.name}")
            _fsync_path(path)
        for path, target in zip(staged, targets):
            os.replace(path, target)
        _fsync_path(directory)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
