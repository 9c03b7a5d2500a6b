"""Atomic file writing: a file is either the old one or the complete new one, never half.

Every writer of the workbench (session CSV, profiles, spectra, reports,
``.ti3``) goes through :func:`atomic_writer`: it writes to a temporary file in
the target's folder, flushes and fsyncs it, gives it the permissions a normal
``open`` would (0666 less the umask), and renames it over the target.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_writer"]


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
