"""The CIE (and ISO) illuminants that colour-science ships, with stable ids.

Ids are ``cie-`` plus colour-science's name lowercased with spaces and dots
turned into ``-``: ``cie-a``, ``cie-d50``, ``cie-d65``, ``cie-fl1`` … ``cie-fl12``,
``cie-fl3-1`` … ``cie-fl3-15``, ``cie-hp1`` …, ``cie-led-b1`` …, ``cie-id65``.
The ISO 7589 photographic sources get ``iso7589-`` ids.
"""

from __future__ import annotations

import re

import colour

from workbench.colorimetry import as_spectral_distribution
from workbench.illuminants.source import Illuminant

__all__ = ["builtin_illuminant_ids", "builtin_illuminant", "builtin_id"]


def builtin_id(name: str) -> str:
    """The stable id of colour-science's illuminant ``name``."""
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
    if slug.startswith("iso-7589-"):
        return "iso7589-" + slug[len("iso-7589-"):]
    return "cie-" + slug


_NAMES = {builtin_id(name): name for name in colour.SDS_ILLUMINANTS.keys()}


def builtin_illuminant_ids() -> list[str]:
    """Ids of the built-in illuminants, in colour-science's order."""
    return list(_NAMES)


def builtin_illuminant(illuminant_id: str) -> Illuminant:
    """The built-in illuminant with this id (KeyError if there is none)."""
    name = _NAMES[illuminant_id]
    sd = as_spectral_distribution(colour.SDS_ILLUMINANTS[name], name=name)
    label = name if name.startswith("ISO") else f"CIE {name}"
    return Illuminant(id=illuminant_id, name=label, kind="cie", sd=sd,
                      description=f"colour-science SDS_ILLUMINANTS[{name!r}]",
                      native_sd=colour.SDS_ILLUMINANTS[name].copy())
