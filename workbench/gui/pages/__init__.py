"""The workbench window's pages, one module each: a view that takes the :class:`workbench.workspace.Workspace` and subscribes to it.

Contract every page follows: ``Page(workspace, parent=None)`` is a ``QWidget``
with a class attribute ``title`` (the flow step's name); it computes nothing
itself (the library does) and may define ``save_screenshot(path)`` when
``QWidget.grab()`` would not show it faithfully (the 3D scene).
"""
