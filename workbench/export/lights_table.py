"""``lights.json``: the level-1 light table of a headset (design §2, level 1).

One record per source: ``id``, ``name``, ``rgb8`` (the engine light colour,
8-bit sRGB-encoded: what a runtime sets), ``linear`` (the same colour as the
engine uses it, linear 0..1), ``XYZ`` (the perfect diffuser under the source,
``Y = k · Y_white``, display scale), ``in_gamut``, ``Rf`` (CIE 2017) and
``CCT`` (K) — the profile's own light entries
(:func:`workbench.profile.light_entries`) plus the linear colour; ``load``
says at which frame load they hold (:data:`workbench.profile.LIGHTS_LOAD`).
"""

from __future__ import annotations

from workbench.display import srgb_decode
from workbench.profile import LIGHTS_LOAD, Profile, light_entries

__all__ = ["LIGHTS_FORMAT", "lights_table"]

LIGHTS_FORMAT = "vr-colour-workbench-lights"


def lights_table(profile: Profile, illuminant_ids) -> dict:
    """The ``lights.json`` document for ``illuminant_ids`` on the profile's display."""
    entries = light_entries(illuminant_ids, profile.display_model(), k=profile.k,
                            observer=profile.observer)
    lights = []
    for entry in entries:
        linear = srgb_decode([v / 255.0 for v in entry["rgb8"]])
        lights.append({**entry, "linear": [round(float(v), 8) for v in linear]})
    return {"format": LIGHTS_FORMAT, "format_version": 1, "device": profile.device.get("name", ""),
            "k": profile.k, "observer": profile.observer,
            "xyz_scale": profile.xyz_scale, "load": LIGHTS_LOAD, "lights": lights}
