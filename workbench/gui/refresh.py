"""A hidden page's redraw put off until the page is shown.

After a calibration the session, the diagnosis and the profile change one
after the other, and every page that follows the workspace redrew at once, in
the window's thread, whether it was on screen or not: at the end of a paper-plan
run the Gamut page redrew three times and the Illuminants page recomputed its
ColorChecker swatches and started its rows' worker, while the window showed the
Fit & diagnose page (``bench gui``: the run's largest event-loop stall,
116–171 ms, was there).
:class:`RedrawWhenShown` redraws a visible page at once and a hidden one once,
when it is next shown, before it is painted.
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QEvent, QObject
from PySide6.QtWidgets import QWidget

__all__ = ["RedrawWhenShown"]


class RedrawWhenShown(QObject):
    """Call ``redraw`` now if ``page`` is visible, otherwise once when ``page`` is next shown.

    Call the object itself where the page would redraw (a workspace event);
    :meth:`flush` redraws now if a redraw is owed (a public accessor of the page
    that reads what the redraw computes).
    """

    def __init__(self, page: QWidget, redraw: Callable[[], None]):
        super().__init__(page)
        self._page = page
        self._redraw = redraw
        self.owed = False
        page.installEventFilter(self)

    def __call__(self) -> None:
        if self._page.isVisible():
            self.owed = False
            self._redraw()
        else:
            self.owed = True

    def flush(self) -> None:
        """Redraw now if a redraw was put off."""
        if self.owed:
            self.owed = False
            self._redraw()

    def eventFilter(self, watched, event) -> bool:  # noqa: N802 - Qt's name
        if watched is self._page and event.type() == QEvent.Type.Show:
            self.flush()
        return False
