"""Example profiles and the profile JSON Schema, shipped as package data.

- ``vrprofile.schema.json``: the JSON Schema every ``*.vrprofile.json`` follows.
- ``htc-vive-paper.vrprofile.json``: the HTC Vive of Díaz-Barrancas et al. (2020),
  Table 1, written by :func:`workbench.profile.paper_vive_profile`.
- ``simulated-headset.vrprofile.json``: the simulated headset of ``make demo``
  (10 % channel interaction, 0.6 % black) calibrated and diagnosed: an extended
  model, written by :func:`workbench.profile.simulated_headset_profile`.
"""

from pathlib import Path

__all__ = ["PROFILES_DIR", "SCHEMA_PATH", "example_profile_path"]

PROFILES_DIR = Path(__file__).resolve().parent
SCHEMA_PATH = PROFILES_DIR / "vrprofile.schema.json"


def example_profile_path(name: str) -> Path:
    """Path of a shipped example profile, e.g. ``"htc-vive-paper"``."""
    path = PROFILES_DIR / f"{name}.vrprofile.json"
    if not path.is_file():
        known = sorted(p.name.removesuffix(".vrprofile.json") for p in PROFILES_DIR.glob("*.vrprofile.json"))
        raise FileNotFoundError(f"no example profile {name!r}; shipped: {known}")
    return path
