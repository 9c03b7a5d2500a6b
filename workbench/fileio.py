"""Atomic file writing: a file is either the old one or the complete new one, never half.

- :func:`atomic_writer` (one file we write ourselves: session CSV, profiles,
  spectra, reports, ``.ti3``) writes to a temporary file in the target's
  folder, flushes and fsyncs it, gives it the permissions a normal ``open``
  would (0666 less the umask), and renames it over the target.
- :func:`atomic_output` (files a library writes by path, possibly several
  that name each other, such as ENVI's header and data) stages them in a
  hidden folder beside the targets under the targets' own names, fsyncs them,
  and renames them in the order given (pass a header last, so that it always
  points at complete data).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["atomic_writer", "atomic_output"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_writer(path, mode: str = "w", *, encoding: str | None = "utf-8", newline: str | None = None):
    """Open a temporary file to write ``path`` atomically; yields the open file.

    ``mode`` is ``"w"`` (text; ``encoding`` and ``newline`` apply) or ``"wb"``.
    The target appears only when the ``with`` block ends without an exception.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_writer mode must be 'w' or 'wb', not {mode!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        text = {"encoding": encoding, "newline": newline} if mode == "w" else {}
        with os.fdopen(fd, mode, **text) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


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
