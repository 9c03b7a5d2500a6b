"""The user's own light sources (measured, imported, synthesized), kept between sessions.

One directory holds one CSV spectrum per source (``<id>.csv``, the format of
:func:`workbench.illuminants.files.write_spectrum_csv`, at the working
sampling 380–780 nm, 1 nm, so a stored source reads back exactly as it was
used) and ``library.json``
with each source's name, kind and description. The directory is
``platformdirs.user_data_dir("vr-colour-workbench")/illuminants`` unless the
environment variable :data:`USER_LIBRARY_ENV` names another (tests point it at
``tmp_path``). Ids start with :data:`USER_ID_PREFIX`, so they never collide
with the built-in library; :func:`resolve_illuminant` takes either.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from workbench.colorimetry import as_spectral_distribution
from workbench.errors import InputError, WorkbenchError
from workbench.fileio import atomic_writer
from workbench.illuminants import get_illuminant
from workbench.illuminants.files import read_spectrum_csv, write_spectrum_csv
from workbench.illuminants.source import SOURCE_KINDS, Illuminant

__all__ = [
    "USER_LIBRARY_ENV",
    "USER_ID_PREFIX",
    "UserLibrary",
    "user_library_dir",
    "resolve_illuminant",
]

USER_LIBRARY_ENV = "VR_WORKBENCH_USER_LIBRARY"
"""Environment variable naming the user library's directory (overrides platformdirs)."""

USER_ID_PREFIX = "user-"
"""Every user-library id starts with this."""

_INDEX = "library.json"


def user_library_dir() -> Path:
    """Where the user library lives (:data:`USER_LIBRARY_ENV`, else the platform's user data dir)."""
    override = os.environ.get(USER_LIBRARY_ENV)
    if override:
        return Path(override)
    import platformdirs

    return Path(platformdirs.user_data_dir("vr-colour-workbench", appauthor=False)) / "illuminants"


def _slug(text: str) -> str:
    slug = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return slug or "source"


class UserLibrary:
    """The persistent user library in ``root`` (default :func:`user_library_dir`).

    Parameters
    ----------
    root : path, optional
    """

    def __init__(self, root=None):
        self.root = Path(root) if root is not None else user_library_dir()

    # -- index ----------------------------------------------------------------
    def _index(self) -> dict:
        path = self.root / _INDEX
        if not path.is_file():
            return {}
        try:
            index = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as error:
            raise WorkbenchError(f"{path}: the user light-source library index is unreadable "
                                 f"({error}). Fix or delete the file (the spectra beside it "
                                 "stay)") from None
        if not isinstance(index, dict):
            raise WorkbenchError(f"{path}: expected a JSON object of sources. Fix or delete the file")
        return index

    def _write_index(self, index: dict) -> None:
        self.root.mkdir(parents=True, exist_ok=True)
        with atomic_writer(self.root / _INDEX) as handle:
            json.dump(index, handle, indent=2, sort_keys=True)

    # -- queries ----------------------------------------------------------------
    def ids(self) -> list[str]:
        """The ids in the library, in the order they were added."""
        index = self._index()
        return sorted(index, key=lambda i: index[i].get("added", 0))

    def __contains__(self, source_id: str) -> bool:
        return source_id in self._index()

    def get(self, source_id: str) -> Illuminant:
        """The source ``source_id`` (a :class:`InputError` naming the known ids if absent)."""
        index = self._index()
        if source_id not in index:
            known = ", ".join(index) or "none yet"
            raise InputError(f"no light source {source_id!r} in the user library {self.root} "
                             f"(it has: {known}); measure or import it first")
        entry = index[source_id]
        raw = read_spectrum_csv(self.root / entry["file"])
        return Illuminant(id=source_id, name=entry["name"], kind=entry["kind"],
                          sd=as_spectral_distribution(raw, name=entry["name"]),
                          description=entry.get("description", ""))

    # -- changes ----------------------------------------------------------------
    def add(self, illuminant: Illuminant, name: str | None = None) -> str:
        """Store ``illuminant`` (its working-range spectrum) under a new id; returns the id."""
        if illuminant.kind not in SOURCE_KINDS:
            raise InputError(f"unknown source kind {illuminant.kind!r}; use one of {SOURCE_KINDS}")
        name = (name or illuminant.name or "source").strip()
        index = self._index()
        base = USER_ID_PREFIX + _slug(name)
        source_id, n = base, 2
        while source_id in index:
            source_id, n = f"{base}-{n}", n + 1
        self.root.mkdir(parents=True, exist_ok=True)
        file_name = f"{source_id}.csv"
        write_spectrum_csv(illuminant.sd, self.root / file_name)
        index[source_id] = {"name": name, "kind": illuminant.kind, "file": file_name,
                            "description": illuminant.description,
                            "added": max([e.get("added", 0) for e in index.values()] + [0]) + 1}
        self._write_index(index)
        return source_id

    def remove(self, source_id: str) -> None:
        """Delete ``source_id`` and its spectrum file."""
        index = self._index()
        if source_id not in index:
            raise InputError(f"no light source {source_id!r} in the user library {self.root}")
        entry = index.pop(source_id)
        self._write_index(index)
        (self.root / entry["file"]).unlink(missing_ok=True)


def resolve_illuminant(source_id: str, library: UserLibrary | None = None) -> Illuminant:
    """A source by built-in id, user-library id (``user-…``) or spectrum file path."""
    if str(source_id).startswith(USER_ID_PREFIX):
        return (library or UserLibrary()).get(str(source_id))
    return get_illuminant(source_id)
