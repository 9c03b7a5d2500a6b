"""``diagnose`` and ``predict``: what the display model gets wrong, and the model in use."""

from __future__ import annotations

import csv
import io
import json
import sys
from pathlib import Path

import numpy as np

from workbench.errors import InputError

__all__ = ["register", "export_profile"]


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "diagnose", help="find what the paper's display model gets wrong, extend it, measure the gain",
        description="Diagnose a session (session CSV, Argyll .ti3, Psychtoolbox .mat, or a "
                    "measurement directory): name the physical effects the gamma + 3x3 model "
                    "misses, fit the extended model, and score both on the validation colours.")
    parser.add_argument("session", help="session CSV, .ti3, .mat or measurement directory")
    parser.add_argument("--json", action="store_true", help="machine-readable output (design §5)")
    parser.add_argument("--export", metavar="PROFILE",
                        help="write the extended model's profile (the baseline's if nothing was found)")
    parser.add_argument("--report", metavar="FILE.html", help="write a self-contained HTML report")
    parser.add_argument("--follow-up", metavar="FILE.csv",
                        help="write the smallest follow-up measurement that identifies what the diagnosis "
                             "left unidentified, as a plan file (kind,r,g,b[,window,sr,sg,sb]; header only "
                             "when nothing is left), and print its summary; measure it into the session's "
                             "directory with measure --add-plan FILE.csv --out DIR")
    parser.set_defaults(handler=_diagnose)

    predict = subparsers.add_parser(
        "predict", help="XYZ a profile predicts for DAC values (CSV r,g,b[,window[,sr,sg,sb]] on "
                        "stdin), or --inverse",
        description="Read CSV r,g,b[,window[,sr,sg,sb]] (DAC 0..255; window: the patch's fraction "
                    "of the field, default 1 = full field; sr,sg,sb: the surround's DAC values, "
                    "default black; optional header naming the columns) on standard input; write "
                    "CSV X,Y,Z on standard output, as the profile's display model predicts, times "
                    "the profile's APL curve gain(L)/gain(L_ref) for a window or a lit surround "
                    "(a profile whose diagnosis tested apl-dependence and did not find it "
                    "predicts any frame as full field; one never tested for it predicts "
                    "full-field patches only). With "
                    "--inverse, read X,Y,Z (the profile's scale) and write the float DAC r,g,b "
                    "of the display inverse (the function display_inverse.cube samples; out of "
                    "gamut: clipped per channel, counted on standard error).")
    predict.add_argument("profile", help="a .vrprofile.json")
    predict.add_argument("--inverse", action="store_true",
                         help="CSV X,Y,Z in, CSV r,g,b (DAC 0..255, float) out")
    predict.set_defaults(handler=_predict)


def export_profile(diagnosis, path) -> Path:
    """Write the profile of ``diagnosis`` (:func:`workbench.profile.profile_from_diagnosis`) to ``path``."""
    from workbench.profile import profile_from_diagnosis, save_profile

    return save_profile(profile_from_diagnosis(diagnosis), path)


def _finding_line(i, finding) -> str:
    z = finding["z"]
    parts = [f"z {z:.1f}" if z is not None else "", f"impact {finding['impact_dE00']:.2f} ΔE00"
             if finding["impact_dE00"] is not None else ""]
    figures = ", ".join(p for p in parts if p)
    cause = finding.get("consequence_of")
    name = finding["effect"] + (f" — consequence of {cause}" if cause else "")
    from workbench.diagnostics.report import split_consequence

    evidence, why = split_consequence(finding)
    line = f"finding {i} {name} ({figures}; score {finding['score']:.1f}): {evidence}"
    return line + (f"\n          ← {why}" if why else "")


def _model_lines(result) -> list[str]:
    """Which model the profile exports and why, and every candidate's cross-validated error."""
    from workbench.diagnostics.model_choice import PRIMARIES_AS_MEASURED

    choice = result.get("model_choice")
    if not choice:
        return []
    scores = ", ".join(f"{name} {'—' if value is None else f'{value:.3f}'}"
                       + (" (exported)" if name == choice["chosen"] else "")
                       for name, value in choice["cv_mean_dE00"].items())
    return [f"model     {choice['chosen']} exported: {choice['reason']}",
            f"          cross-validated mean ΔE00 on the fit rows: {scores}",
            f"          full-drive primaries {choice.get('primaries') or PRIMARIES_AS_MEASURED}"]


def _print_text(diagnosis) -> None:
    result = diagnosis.to_json()
    base, ext = result["baseline"], result["extended"]
    print(f"session {result['session']['source']}: {result['session']['measurements']} "
          f"measurements, {result['session']['validation']} held out for validation")
    print(f"noise     {result['noise']['summary']}")
    significance = result["significance"]
    print(f"tests     a finding needs z above {_critical(result):.2f} (family-wise false-finding "
          f"rate {100 * significance['family_alpha']:.0f} %, {significance['method']}) and an "
          f"impact of at least {significance['materiality_floor_dE00']:g} mean ΔE00 on a "
          f"{significance['materiality_colours']}")
    for note in result["untested"]:
        print(f"untested  {note['effect']}: {note['reason']}")

    def figures(block):
        v = block["validation"]
        return ("no validation colours" if v is None else
                f"ΔE00 mean {v['mean_dE00']:.2f}, p95 {v['p95_dE00']:.2f}, max {v['max_dE00']:.2f}")

    print(f"baseline  {base['model']}: {figures(base)}")
    if not result["findings"]:
        print("findings  none beyond noise: the paper's model is adequate for this display")
    terms = {t["effect"]: t for t in ext["terms"]}
    attribution = result["attribution"]
    contributions = ({t["effect"]: t for t in attribution["terms"]} if attribution else {})
    for i, finding in enumerate(result["findings"], start=1):
        print(_finding_line(i, finding))
        if finding["effect"] in terms:
            term = terms[finding["effect"]]
            line = f"          → {term['term']}, fitted on {term['fitted_on']}"
            if finding["effect"] in contributions:
                line += (f"; without it held-out mean ΔE00 would be "
                         f"{contributions[finding['effect']]['mean_dE00_without']:.2f}")
            print(line)
        elif finding["cross_validation"]:
            print(f"          → {finding['cross_validation']}")
    near = [c for c in result["checked"] if c["testable"] and c["significant"]]
    for check in near:
        print(f"not material  {check['effect']} (z {check['z']:.1f}, impact "
              f"{check['impact_dE00']:.3f} ΔE00 below the floor): {check['evidence']}")
    print(f"extended  {ext['model']}: {figures(ext)}  [{ext['protocol']}]")
    for line in _model_lines(result):
        print(line)
    if attribution:
        print(f"refit     the extension's fitting with no term: ΔE00 mean "
              f"{attribution['no_terms_refit']['mean_dE00']:.2f} (what better use of the same rows "
              "buys without any named effect)")
    if result["fallback"] is not None:
        print(f"fallback  {result['fallback']['model']}: {figures(result['fallback'])}  "
              f"[{result['fallback']['protocol'].split(':')[0]}]")
    gain = result["gain"]["mean_dE00_reduction_pct"]
    if gain is not None:
        print(f"gain      mean ΔE00 reduced by {gain:.0f} % on colours neither model was fitted on")
    _print_apl(result)
    print("(CIEDE2000 in CIELAB whose white is the measured display white)")


def _print_apl(result) -> None:
    """The APL curve and its held-out error: the closing note of a session with windows."""
    apl = result.get("apl")
    if not apl or apl["curve"] is None:
        return
    curve = apl["curve"]
    print(f"APL curve {curve['formula']}: L0 {curve['knee']:.3g}, n {curve['sharpness']:.3g}, "
          f"a {curve['exponent']:.3g} (load L: 0 black, 1 full-field white; the model holds at "
          "the reference load, each patch full field)")
    for holdout in apl["holdout"]:
        print(f"held out  leave one {holdout['by']} out ({len(holdout['folds'])} folds): "
              f"{holdout['luminance_error_pct']:.1f} % of luminance, {holdout['mean_dE00']:.2f} "
              f"ΔE00 mean (p95 {holdout['p95_luminance_error_pct']:.1f} %, "
              f"{holdout['p95_dE00']:.2f}); without a load term "
              f"{holdout['without_load_term']['luminance_error_pct']:.1f} %, "
              f"{holdout['without_load_term']['mean_dE00']:.2f} ΔE00")


def _print_load_only(diagnosis) -> None:
    """A session with windows or surrounds but no display model: apl-dependence alone."""
    from workbench.diagnostics.selection import APL_TERM

    result = diagnosis.to_json()
    print(f"session {result['session']['source']}: {result['session']['measurements']} "
          "measurements; no display model can be fitted (no full-field sweep of each channel): "
          "apl-dependence tested alone")
    print(f"noise     {result['noise']['summary']}")
    significance = result["significance"]
    finding = (result["findings"] or result["checked"] or [None])[0]
    if finding is not None and finding["critical_z"] is not None:
        print(f"tests     a finding needs z above {finding['critical_z']:.2f} (family-wise "
              f"false-finding rate {100 * significance['family_alpha']:.0f} %, "
              f"{significance['method']}) and an impact of at least "
              f"{significance['materiality_floor_dE00']:g} mean ΔE00 between "
              f"{significance['materiality_colours']}")
    for note in result["untested"]:
        print(f"untested  {note['effect']}: {note['reason']}")
    if not result["findings"]:
        print("findings  none beyond noise")
    for i, found in enumerate(result["findings"], start=1):
        print(_finding_line(i, found))
        print(f"          → {APL_TERM}")
    for check in result["checked"]:
        if check["testable"]:
            print(f"checked   {check['effect']} (z {check['z']:.1f}): {check['evidence']}")
    _print_apl(result)
    print("(CIEDE2000 in CIELAB whose white is the brightest patch's zero-load output)")


def _critical(result) -> float:
    values = [f["critical_z"] for f in result["findings"] + result["checked"]
              if f["testable"] and f["effect"] != "unexplained-residual"
              and f["critical_z"] is not None]
    return values[0] if values else float("nan")


def _diagnose(args) -> int:
    from workbench.diagnostics.load_only import LoadOnlyDiagnosis, diagnose_what_it_can
    from workbench.session_readers import read_session

    diagnosis = diagnose_what_it_can(read_session(args.session))
    load_only = isinstance(diagnosis, LoadOnlyDiagnosis)
    if load_only and (args.export or args.report):
        raise InputError(f"{args.session}: no display model can be fitted (no full-field sweep "
                         "of each channel), so there is no profile or report to write; measure "
                         "plan 'paper+apl', or drop --export/--report")
    follow_up = None
    if args.follow_up:
        from workbench.diagnostics.follow_up import propose_follow_up

        follow_up = propose_follow_up(diagnosis)
    if args.json:
        document = diagnosis.to_json()
        if follow_up is not None:
            document["follow_up"] = follow_up.to_json()
        json.dump(document, sys.stdout, indent=1)
        print()
    elif load_only:
        _print_load_only(diagnosis)
    else:
        _print_text(diagnosis)
    if args.export:
        path = export_profile(diagnosis, args.export)
        print(f"wrote profile {path}", file=sys.stderr)
    if args.report:
        from workbench.diagnostics.report import write_report

        path = write_report(diagnosis, args.report)
        print(f"wrote report {path}", file=sys.stderr)
    if follow_up is not None:
        _write_follow_up(follow_up, args)
    return 0


def _write_follow_up(follow_up, args) -> None:
    """Write the follow-up plan file and say what it holds (stdout, or stderr beside --json)."""
    path = follow_up.write(args.follow_up)
    out = sys.stderr if args.json else sys.stdout
    for line in follow_up.lines():
        print(f"follow-up {line}" if not line.startswith("  ") else f"          {line.strip()}", file=out)
    if follow_up.patches:
        where = args.session if Path(args.session).is_dir() else "DIR"
        print(f"wrote follow-up plan {path} ({follow_up.patch_count} patches); measure it into the "
              f"session with: python -m workbench measure ... --out {where} --add-plan {path}", file=out)
    else:
        print(f"wrote follow-up plan {path}: the header only, nothing to measure", file=out)


def _read_triplets(what: str, example: str) -> np.ndarray:
    """CSV rows of three finite numbers on standard input (a header line is skipped)."""
    rows = []
    for number, row in enumerate(csv.reader(io.StringIO(sys.stdin.read())), start=1):
        cells = [cell.strip() for cell in row]
        if not cells or not any(cells):
            continue
        try:
            values = [float(v) for v in cells[:3]]
        except ValueError:
            if number == 1:
                continue  # header
            raise InputError(f"stdin line {number}: {row!r} is not {what} numbers; "
                             f"give one triplet per line, e.g. {example}") from None
        if len(values) != 3:
            raise InputError(f"stdin line {number}: need 3 values {what}, got {len(values)}")
        if not all(np.isfinite(values)):
            raise InputError(f"stdin line {number}: {row!r} holds NaN or infinity; give finite "
                             f"{what} values")
        rows.append(values)
    if not rows:
        raise InputError(f"no {what} rows on standard input; e.g. echo {example} | "
                         "python -m workbench predict PROFILE" + (" --inverse" if what == "X,Y,Z"
                                                                 else ""))
    return np.array(rows)


def _predict(args) -> int:
    from workbench.profile import load_profile

    profile = load_profile(args.profile)
    model = profile.display_model()
    writer = csv.writer(sys.stdout, lineterminator="\n")
    if args.inverse:
        XYZ = _read_triplets("X,Y,Z", "40,42,45")
        dac = model.inverse(XYZ)
        clipped = int(np.count_nonzero(~model.in_gamut(XYZ)))
        writer.writerow(["r", "g", "b"])
        for value in dac:
            writer.writerow([f"{v:.4f}" for v in value])
        if clipped:
            print(f"{clipped} of {len(XYZ)} colour(s) outside the display gamut: clipped per "
                  "channel in linear drive", file=sys.stderr)
        return 0
    from workbench.apl.predict import predict_XYZ_on_surround, read_predict_rows

    XYZ = predict_XYZ_on_surround(model.forward, read_predict_rows(sys.stdin.read()),
                                  profile.apl_curve(), load_independent=profile.apl_tested_absent)
    writer.writerow(["X", "Y", "Z"])
    for value in XYZ:
        writer.writerow([f"{v:.6g}" for v in value])
    return 0
