"""Spectral colour management workbench for virtual reality.

Science and application live here; device I/O lives in :mod:`instruments`, the
Qt GUI in :mod:`workbench.gui` (the only subpackage that imports Qt).

Internal scale (one, everywhere): tristimulus values are absolute, in cd/m²
for Y (or relative with the display white at ``Y = 100`` where no absolute
figure exists); DAC values are floats on 0..255; linear light and reflectance
are on 0..1; wavelengths are in nanometres.
"""

__all__ = ["__version__"]

__version__ = "0.1.0"
