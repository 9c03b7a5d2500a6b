"""``illuminants list|show|export``: the light-source library from the command line."""

from __future__ import annotations

import json
import sys

from workbench.colorimetry import DEFAULT_K, OBSERVERS
from workbench.illuminants import (
    get_illuminant,
    illuminant_metrics,
    list_illuminants,
    write_illuminant_file,
)

__all__ = ["register"]


def register(subparsers) -> None:
    parser = subparsers.add_parser("illuminants", help="the light-source library",
                                   description="List, inspect and export light sources.")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB", required=True)

    listing = verbs.add_parser("list", help="every source id (with --metrics: Rf, CCT, light RGB)")
    listing.add_argument("--metrics", action="store_true",
                         help="also compute Rf, CCT, rgb8 and level-1 ΔE00 (a few seconds)")
    listing.add_argument("--json", action="store_true", help="machine-readable output")
    listing.set_defaults(handler=_list)

    show = verbs.add_parser("show", help="metrics of one source",
                            description="Metrics of a source given by id or by a .csv/.xml file.")
    show.add_argument("id", help="library id (see 'illuminants list') or a spectrum file")
    show.add_argument("--json", action="store_true", help="machine-readable output")
    show.add_argument("--spectrum", action="store_true", help="include the spectrum (380–780 nm)")
    show.add_argument("--profile", help="a .vrprofile.json: also give the light RGB for that headset")
    show.add_argument("--k", type=float, default=DEFAULT_K,
                      help=f"scene-white factor (default {DEFAULT_K})")
    show.add_argument("--observer", choices=sorted(OBSERVERS), default="cie1931-2")
    show.set_defaults(handler=_show)

    export = verbs.add_parser("export", help="write a source as CSV or IES TM-27 XML")
    export.add_argument("id")
    export.add_argument("out", help="file ending in .csv or .xml")
    export.set_defaults(handler=_export)


def _list(args) -> int:
    ids = list_illuminants()
    if not args.metrics:
        records = [{"id": i, "name": get_illuminant(i).name, "kind": get_illuminant(i).kind}
                   for i in ids]
        if args.json:
            json.dump(records, sys.stdout, indent=1)
            print()
        else:
            for record in records:
                print(f"{record['id']:<40} {record['kind']:<12} {record['name']}")
        return 0
    from tqdm import tqdm

    metrics = [illuminant_metrics(get_illuminant(i))
               for i in tqdm(ids, desc="metrics", unit="source", file=sys.stderr, leave=False,
                             disable=not sys.stderr.isatty())]
    if args.json:
        json.dump([m.to_json() for m in metrics], sys.stdout, indent=1)
        print()
        return 0
    print(f"{'id':<40} {'Rf':>6} {'Rg':>6} {'CCT K':>7} {'Duv':>8}  {'rgb8 sRGB':<15} "
          f"{'L1 ΔE00 mean/max':>17}")
    for m in metrics:
        rgb = ",".join(str(v) for v in m.rgb8_srgb)
        print(f"{m.id:<40} {m.Rf:6.1f} {m.Rg:6.1f} {m.CCT:7.0f} {m.Duv:8.4f}  {rgb:<15} "
              f"{m.level1_mean_dE00:8.2f}/{m.level1_max_dE00:<8.2f}")
    print("ΔE00: level 1 on the ColorChecker + 99 CIE 2017 samples, CIELAB white = the perfect "
          "diffuser under each source")
    return 0


def _load_note(profile) -> str:
    """At which load the profile's light colours hold, and what the APL curve says off it."""
    from workbench.profile import LIGHTS_LOAD

    curve = profile.apl_curve()
    if curve is None and profile.apl_tested_absent:
        return LIGHTS_LOAD + ("; the profile's diagnosis tested apl-dependence and did not find "
                              "it, so they hold on any frame")
    if curve is None:
        return LIGHTS_LOAD + " (the profile has no APL curve)"
    white = curve.relative_gain([[255.0, 255.0, 255.0]], [0.1], [[0.0, 0.0, 0.0]])[0]
    return (LIGHTS_LOAD + f"; the profile's APL curve: a white in a 10 % window on black "
            f"shows {white:.2f}× its full-field output")


def _show(args) -> int:
    illuminant = get_illuminant(args.id)
    display = profile = None
    if args.profile:
        from workbench.profile import load_profile

        profile = load_profile(args.profile)
        display = profile.display_model()
    metrics = illuminant_metrics(illuminant, display, k=args.k, observer=args.observer)
    record = metrics.to_json()
    if profile is not None:
        record["load"] = _load_note(profile)
    if args.spectrum:
        record["spectrum"] = {"wavelength": illuminant.wavelengths.tolist(),
                              "value": illuminant.values.tolist()}
    if args.json:
        json.dump(record, sys.stdout, indent=1)
        print()
        return 0
    print(f"{metrics.name}  [{metrics.id}, {metrics.kind}]")
    if illuminant.description:
        print(f"  {illuminant.description}")
    print(f"  CIE Rf {metrics.Rf:.1f}   Rg {metrics.Rg:.1f}   CCT {metrics.CCT:.0f} K   "
          f"Duv {metrics.Duv:+.4f}")
    print(f"  xy {metrics.xy[0]:.4f}, {metrics.xy[1]:.4f}   XYZ "
          + ", ".join(f"{v:.2f}" for v in metrics.XYZ) + f"  (k = {metrics.k}, {metrics.observer})")
    print(f"  light rgb8: sRGB {metrics.rgb8_srgb}"
          + (f"   {metrics.display} {metrics.rgb8_display}" if display is not None else "")
          + ("" if metrics.light_in_gamut else "   (clipped: outside the display gamut)"))
    if profile is not None:
        print(f"  ({_load_note(profile)})")
    if metrics.observer != "cie1931-2":
        print("  (light colours and level-1 errors: for the display's CIE 1931 2° observer)")
    for a in metrics.level1:
        print(f"  level-1 ΔE00 on {a.sample_set:<12} mean {a.mean_dE00:5.2f}  p95 {a.p95_dE00:5.2f}"
              f"  max {a.max_dE00:5.2f} ({a.worst_sample})")
    verdict = ("level 1 is enough" if metrics.level1_mean_dE00 < 1.0
               else "level 2 (hyperspectral textures) is needed for faithful colour")
    print(f"  → {verdict} under this source")
    return 0


def _export(args) -> int:
    path = write_illuminant_file(get_illuminant(args.id), args.out)
    print(f"wrote {path}")
    return 0
