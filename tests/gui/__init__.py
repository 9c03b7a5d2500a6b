"""GUI tests: each module calls :func:`require_window` before it imports any Qt widget."""

from __future__ import annotations

import pytest


def require_window(*modules: str) -> None:
    """Skip the calling test module unless PySide6 and ``modules`` import and Qt can open a
    window here (without a display Qt would abort the whole test process, so a child process
    asks first: :func:`~workbench.gui.measure_window.patch_window_unavailable_reason`)."""
    for module in ("PySide6", *modules):
        pytest.importorskip(module)
    from workbench.gui.measure_window import patch_window_unavailable_reason

    unavailable = patch_window_unavailable_reason()
    if unavailable is not None:
        pytest.skip(f"Qt cannot open a window here: {unavailable}", allow_module_level=True)
