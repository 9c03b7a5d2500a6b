"""``ishihara generate|read|score|table5|table6``: the virtual Ishihara test from the command line."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from workbench.errors import InputError

__all__ = ["register"]

_LEVEL_HELP = ("1 or 2: the HMD at that colour-management level; 'physical': the real plate "
               "under the source (default 2)")


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "ishihara", help="virtual Ishihara plates and simulated observers",
        description="Generate hyperspectral Ishihara plates, have simulated normal, anomalous and "
                    "dichromatic observers read them, and reproduce the paper's Tables 5 and 6.")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB", required=True)

    generate = verbs.add_parser("generate", help="write plates as .npz (+ PNG preview)",
                                description="Write each plate as PLATE_NN.npz (label map, dot "
                                            "reflectances, wavelengths) and PLATE_NN.png (its "
                                            "preview on the ideal sRGB display under D65).")
    which = generate.add_mutually_exclusive_group(required=True)
    which.add_argument("--plate", type=int, metavar="N", help="one plate of the paper's set (1-10)")
    which.add_argument("--set", choices=["paper"], help="the paper's 10-plate set")
    generate.add_argument("--out", required=True, help="output directory (created if missing)")
    _plate_options(generate)
    generate.set_defaults(handler=_generate)

    read = verbs.add_parser("read", help="what an observer reads on one plate")
    read.add_argument("plate", help="a plate .npz written by 'ishihara generate'")
    _viewing_options(read)
    read.add_argument("--json", action="store_true", help="machine-readable output")
    read.set_defaults(handler=_read)

    score = verbs.add_parser("score", help="an observer takes the whole test and is classified")
    _viewing_options(score)
    _plate_options(score)
    score.add_argument("--json", action="store_true", help="machine-readable output")
    score.set_defaults(handler=_score)

    table5 = verbs.add_parser("table5", help="the paper's Table 5: dot colours calculated vs "
                                             "measured end to end")
    table5.add_argument("--json", action="store_true", help="machine-readable output")
    table5.set_defaults(handler=_table5)

    table6 = verbs.add_parser("table6", help="the paper's Table 6: simulated observers' readings "
                                             "under D65 and the two-peak source, levels 1 and 2")
    table6.add_argument("--json", action="store_true", help="machine-readable output")
    _plate_options(table6)
    table6.set_defaults(handler=_table6)


def _plate_options(parser) -> None:
    from workbench.ishihara import DEFAULT_PLATE_SIZE, DEFAULT_SEED

    parser.add_argument("--size", type=int, default=DEFAULT_PLATE_SIZE,
                        help=f"plate image size in pixels (default {DEFAULT_PLATE_SIZE})")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED,
                        help=f"base seed of the set; plate N uses seed + N (default {DEFAULT_SEED})")


def _viewing_options(parser) -> None:
    parser.add_argument("--observer", required=True,
                        help="normal, protan, deutan or tritan; protan/deutan take a severity, "
                             "e.g. protan:0.5 (1 = dichromat, the default)")
    parser.add_argument("--illuminant", default="cie-d65",
                        help="light source id or spectrum file (default cie-d65)")
    parser.add_argument("--level", default="2", help=_LEVEL_HELP)


def _viewing(args):
    from workbench.ishihara import Viewing, parse_observer

    return parse_observer(args.observer), Viewing(args.illuminant, args.level)


def _dump(record) -> None:
    json.dump(record, sys.stdout, indent=1)
    print()


def _generate(args) -> int:
    from workbench.ishihara import (
        generate_plate,
        paper_plate_set_specs,
        save_plate,
        write_plate_preview,
    )

    specs = paper_plate_set_specs()
    if args.plate is not None and not 1 <= args.plate <= len(specs):
        raise InputError(f"--plate {args.plate}: the paper's set has plates 1 to {len(specs)}")
    chosen = specs if args.set else (specs[args.plate - 1],)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for spec in chosen:
        plate = generate_plate(spec, args.size, args.seed + spec.number)
        npz = save_plate(plate, out / f"plate_{spec.number:02d}.npz")
        png = write_plate_preview(plate, out / f"plate_{spec.number:02d}.png")
        print(f"plate {spec.number:2d} {spec.kind:<15} normal {spec.normal:>2}  protan "
              f"{spec.protan:>2}  deutan {spec.deutan:>2}  {plate.layout.count} dots  → {npz}, "
              f"{png.name}")
    return 0


def _read(args) -> int:
    from workbench.ishihara import load_plate, read_plate

    plate = load_plate(args.plate)
    observer, viewing = _viewing(args)
    reading = read_plate(plate, observer, viewing)
    spec = plate.spec
    reference = {"normal": spec.normal, "protan": spec.protan, "deutan": spec.deutan}
    record = {"plate": plate.spec.number, "kind": plate.spec.kind, "observer": observer.name,
              "observer_description": observer.description, "illuminant": viewing.illuminant,
              "level": viewing.path, "answer": reading.answer, "reason": reading.reason,
              "contrast_jnd": round(reading.contrast_jnd, 2), "glyph_match": round(reading.match, 3),
              "best_guess": reading.best_guess, "reference_answers": reference}
    if args.json:
        _dump(record)
        return 0
    print(f"plate {plate.spec.number} ({plate.spec.kind}) seen by a {observer.description}, "
          f"{viewing.describe()}:")
    print(f"  reads {reading.answer!r} ({reading.reason}; figure-ground contrast "
          f"{reading.contrast_jnd:.1f} JND, glyph match {reading.match:.2f} for "
          f"{reading.best_guess!r})")
    print("  reference answers (Ishihara's instructions): " + ", ".join(
        f"{kind} {answer!r}" for kind, answer in reference.items()))
    return 0


def _score(args) -> int:
    from workbench.ishihara import generate_plate_set, take_test

    observer, viewing = _viewing(args)
    plates = generate_plate_set(args.size, args.seed)
    exam = take_test(plates, observer, viewing)
    score = exam.score
    record = {"observer": observer.name, "observer_description": observer.description,
              "illuminant": viewing.illuminant, "level": viewing.path,
              "answers": list(score.answers), "read_normally": list(score.read_normally),
              "screening_read_normally": score.screening_read_normally,
              "screening_plates": score.screening_plates,
              "normal_at_least": score.normal_at_least,
              "deficient_at_most": score.deficient_at_most,
              "classification": score.classification,
              "contrasts_jnd": [round(r.contrast_jnd, 2) for r in exam.readings]}
    if args.json:
        _dump(record)
        return 0
    print(f"{observer.description}, {viewing.describe()}")
    print("  plate   " + " ".join(f"{p.spec.number:>3}" for p in plates))
    print("  answer  " + " ".join(f"{a:>3}" for a in score.answers))
    print("  normal  " + " ".join(f"{p.spec.normal:>3}" for p in plates))
    print(f"  screening plates read normally: {score.screening_read_normally} of "
          f"{score.screening_plates} (normal ≥ {score.normal_at_least}, deficient ≤ "
          f"{score.deficient_at_most}, Ishihara's 17/21 and 13/21)")
    print(f"  classification: {score.classification}")
    return 0


def _xyY(values) -> str:
    return f"{values[0]:.4f} {values[1]:.4f} {values[2]:5.1f}"


def _table5(args) -> int:
    from workbench.ishihara import table5

    result = table5()
    if args.json:
        _dump(result.to_json())
        return 0
    print("Table 5 — dot colours of plate 3 under CIE D65: calculated vs measured end to end")
    print(f"  (plate cube → spectral basis, K = {result.basis_components[0]} → level-2 texture "
          "relit for D65 → texel at the dot's centre → engine → headset → CS-2000 emulator)")
    print(f"  headset: {result.headset}")
    print("  diagnosis of its calibration: " + ("; ".join(e for e, _ in result.findings)
                                                 or "nothing beyond noise"))
    print(f"  baseline model: {result.baseline_display}")
    print(f"  extended model: {result.display} (what the workbench uses)")
    print(f"{'dot':<4} {'name':<19} {'calculated':>20} {'measured (extended)':>20} {'ΔE00':>5} "
          f"{'ΔE00 baseline':>13}   {'paper calculated':>20} {'paper measured':>20} {'ΔE00':>5}")
    for r in result.rows:
        print(f"{r.dot:<4} {r.name:<19} {_xyY(r.calculated):>20} {_xyY(r.measured):>20} "
              f"{r.dE00:5.2f} {r.baseline_dE00:13.2f}   {_xyY(r.paper_calculated):>20} "
              f"{_xyY(r.paper_measured):>20} {r.paper_dE00:5.2f}")
    print(f"mean ΔE00: ours {result.mean_dE00:.2f} with the extended model, "
          f"{result.baseline_mean_dE00:.2f} with the baseline (the diagnosis removes "
          f"{result.gain_pct:.0f} %); paper {result.paper_mean_dE00:.2f}")
    print("\nColours of our generated plate 3 (designed on confusion lines), same path:")
    for r in result.plate3_rows:
        print(f"     {r.dot:<19} {_xyY(r.calculated):>20} {_xyY(r.measured):>20} {r.dE00:5.2f} "
              f"{r.baseline_dE00:13.2f}")
    print(f"mean ΔE00: {result.plate3_mean_dE00:.2f} extended, "
          f"{result.plate3_baseline_mean_dE00:.2f} baseline")
    print(f"Basis-path texels vs the full-band level-2 texture: at most "
          f"{result.max_texel_difference} count(s) apart.")
    print("x, y: CIE 1931; Y: perfect diffuser = 100. ΔE00 in CIELAB whose white is XYZ_t of the "
          "perfect diffuser under D65.")
    return 0


def _table6(args) -> int:
    from workbench.ishihara import PAPER_TABLE6_REFERENCE, table6

    result = table6(args.size, args.seed)
    if args.json:
        _dump(result.to_json())
        return 0
    header = " ".join(f"{f'P{i}':>3}" for i in range(1, 11))
    print("Table 6 — readings of the 10-plate set")
    print(f"{'paper reference':<28} {header}")
    for r in PAPER_TABLE6_REFERENCE:
        print(f"  {r.observer} {r.qualification:<22} " + " ".join(f"{a:>3}" for a in r.answers))
    for finding in result.findings:
        print(f"\n{finding.viewing.describe()}")
        for r in result.rows_for(finding.viewing):
            marks = ["= Ref" if r.matches_reference else "≠ Ref"]
            if finding.viewing.path != "physical":
                marks.append("= real plates" if r.matches_physical else
                             f"≠ real plates ({r.physical_classification})")
            print(f"  {r.observer:<26} " + " ".join(f"{a:>3}" for a in r.answers)
                  + f"   {r.classification:<12} {', '.join(marks)}"
                  + (f"; dots moved {r.dot_shift_jnd:.1f} JND, contrast ±"
                     f"{r.max_contrast_change_jnd:.1f}" if finding.viewing.path != "physical"
                     else ""))
        print(f"  → {finding.summary}")
    print("\nSimulated observers: Smith & Pokorny cone fundamentals (CIE 1931), protan/deutan "
          "dichromats by Machado et al. (2009)'s blend; '@ss2000': Stockman & Sharpe (2000) 2° "
          "fundamentals, not linear in CIE 1931 (level 2 is computed for CIE 1931, so for them it "
          "is a metamer: 'dots moved' is the median colour difference of a dot between the HMD "
          "and the real plate, 'contrast ±' the largest change of a figure–ground contrast); "
          f"receptor-noise colour space; plates {result.plate_size} px.")
    return 0
