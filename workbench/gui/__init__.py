"""The Qt GUI: the only subpackage that may import PySide6, pyqtgraph or pyvistaqt.

Everything here is a thin view over models in :mod:`workbench` that the CLI and
the tests use too.
"""
