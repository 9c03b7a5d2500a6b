import numpy as np
import pytest

from workbench.display import (
    DISPLAY_MODELS,
    GammaMatrixDisplay,
    SRGBDisplay,
    display_model_from_parameters,
    fit_display_model,
    fit_power_law,
)
from workbench.errors import InputError
from workbench.session import Session, read_session_csv, write_session_csv

TRUE = GammaMatrixDisplay.from_primaries_xyY(
    [(0.667, 0.332, 30.3), (0.217, 0.710, 75.4), (0.139, 0.051, 7.8)],
    (0.299, 0.315, 100.0), (2.43, 2.38, 2.38))


def synthetic_session(model, rng, noise=0.0):
    kinds, rgb = ["black", "white"], [[0, 0, 0], [255, 255, 255]]
    for channel, kind in enumerate(("ramp-r", "ramp-g", "ramp-b")):
        for level in range(5, 256, 5):
            triplet = [0, 0, 0]
            triplet[channel] = level
            kinds.append(kind)
            rgb.append(triplet)
    for triplet in rng.integers(0, 256, (50, 3)):
        kinds.append("validation")
        rgb.append(list(triplet))
    rgb = np.array(rgb, dtype=float)
    XYZ = model.forward(rgb) * (1 + noise * rng.standard_normal((len(rgb), 3)))
    return Session(kind=np.array(kinds, dtype=object), rgb=rgb, XYZ=XYZ, source="synthetic")


def test_fit_recovers_the_generating_model(rng):
    fitted = fit_display_model(synthetic_session(TRUE, rng), "gamma-matrix")
    np.testing.assert_allclose(fitted.gamma, TRUE.gamma, atol=1e-6)
    np.testing.assert_allclose(fitted.matrix, TRUE.matrix, rtol=1e-9)
    assert np.all(fitted.r_squared > 0.999999)


def test_fit_never_uses_validation_rows(rng):
    session = synthetic_session(TRUE, rng)
    corrupted = Session(kind=session.kind, rgb=session.rgb,
                        XYZ=np.where(session.mask("validation")[:, None], 1e3, session.XYZ))
    np.testing.assert_allclose(fit_display_model(corrupted).matrix, TRUE.matrix, rtol=1e-9)


def test_fit_needs_each_sweep(rng):
    session = synthetic_session(TRUE, rng).without("ramp-g")
    with pytest.raises(InputError, match="ramp-g"):
        fit_display_model(session)


def test_power_law_fit_and_r_squared():
    drive = np.linspace(0.02, 1, 50)
    gamma, r2 = fit_power_law(drive, drive ** 2.2)
    assert gamma == pytest.approx(2.2, abs=1e-6) and r2 == pytest.approx(1.0)


def test_noise_weighted_power_law_fit():
    drive = np.linspace(0.02, 1, 50)
    gamma, r2 = fit_power_law(drive, drive ** 2.2, weighting="noise")
    assert gamma == pytest.approx(2.2, abs=1e-6) and r2 == pytest.approx(1.0)
    with pytest.raises(InputError, match="unknown gamma weighting 'log'; use one of luminance, noise"):
        fit_power_law(drive, drive ** 2.2, weighting="log")


def test_noise_weighted_gamma_is_closer_on_ten_levels_with_relative_noise():
    """With relative noise on ten sweep levels, the noise-weighted γ is the better estimate: in
    luminance the brightest levels decide it (and their noise is the largest in absolute)."""
    drive = np.array([32, 64, 96, 128, 160, 192, 208, 224, 236, 246, 255]) / 255.0
    rng = np.random.default_rng(7)
    errors = {"luminance": [], "noise": []}
    for _ in range(200):
        response = drive ** 2.4 * (1 + 0.003 * rng.standard_normal(drive.size))
        response = response / response[-1]
        for weighting in errors:
            errors[weighting].append(fit_power_law(drive, response, weighting)[0] - 2.4)
    rms = {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in errors.items()}
    assert rms["noise"] < 0.75 * rms["luminance"], rms


@pytest.mark.parametrize("weighting", ["luminance", "noise"])
def test_power_law_fit_reaches_the_least_squares_minimum_scipy_finds_or_a_lower_one(weighting):
    """The closed-form Newton fit against scipy's bounded least squares from the same start, on
    sweeps with noise, a shoulder and a toe: never a higher sum of squares, and where the
    minimum is well defined the same exponent."""
    from scipy.optimize import least_squares

    from workbench.display.tone_curves import noise_weights

    rng = np.random.default_rng(11)
    for trial in range(60):
        drive = np.sort(rng.choice(np.arange(5, 256, 5), int(rng.integers(4, 52)),
                                   replace=False)) / 255.0
        gamma = rng.uniform(1.6, 3.2)
        response = drive ** gamma * (1 + 0.004 * rng.standard_normal(drive.size))
        if trial % 3 == 1:  # a shoulder: compression above 70 % drive
            response = np.where(drive > 0.7, 0.7 ** gamma + 0.4 * (response - 0.7 ** gamma),
                                response)
        elif trial % 3 == 2:  # a toe: light at DAC 0
            response = response + 0.01
        weight = noise_weights(response) if weighting == "noise" else np.ones_like(response)
        fitted, _ = fit_power_law(drive, response, weighting)
        reference = least_squares(lambda g: (drive ** g[0] - response) * weight, x0=[2.2],
                                  bounds=([0.1], [10.0])).x[0]

        def cost(g):
            return float(np.sum(((drive ** g - response) * weight) ** 2))

        assert cost(fitted) <= cost(reference) * (1 + 1e-9), (trial, fitted, reference)
        assert fitted == pytest.approx(reference, rel=1e-3), trial


def test_power_law_fit_holds_to_its_bounds():
    drive = np.linspace(0.1, 1, 10)
    assert fit_power_law(drive, drive ** 14.0)[0] == pytest.approx(10.0)
    assert fit_power_law(drive, np.ones_like(drive))[0] == pytest.approx(0.1)


@pytest.mark.parametrize("model", [TRUE, SRGBDisplay(), SRGBDisplay(Y_white=250.0)])
def test_round_trip_within_half_a_count_in_gamut(model, rng):
    dac = rng.uniform(0, 255, (20000, 3))
    back = model.inverse(model.forward(dac))
    assert np.abs(back - dac).max() < 0.5
    assert np.all(model.in_gamut(model.forward(dac)))


def test_vectorized_shapes():
    dac = np.zeros((4, 5, 3)) + 128
    assert TRUE.forward(dac).shape == (4, 5, 3)
    assert TRUE.inverse(TRUE.forward(dac)).shape == (4, 5, 3)


def test_out_of_gamut_is_clipped_per_channel_and_flagged():
    too_bright = TRUE.white_XYZ * 3
    negative_red = TRUE.matrix @ np.array([-0.2, 0.5, 0.5])
    XYZ = np.array([too_bright, negative_red])
    dac = TRUE.inverse(XYZ)
    assert not TRUE.in_gamut(XYZ).any()
    assert np.all(np.isfinite(dac)) and dac.min() >= 0 and dac.max() <= 255
    assert dac[1, 0] == 0.0  # the negative red drive is clipped to zero
    np.testing.assert_allclose(dac[1, 1:], 255 * 0.5 ** (1 / TRUE.gamma[1:]))


def test_srgb_display_lights_of_the_paper():
    srgb = SRGBDisplay()
    assert srgb.inverse_rgb8([80.81, 85.00, 92.57]).tolist() == [237, 237, 237]
    assert srgb.inverse_rgb8([81.98, 85.00, 70.11]).tolist() == [255, 235, 205]


def test_registry_and_parameters_round_trip():
    assert {"gamma-matrix", "srgb"} <= set(DISPLAY_MODELS)
    again = display_model_from_parameters("gamma-matrix", TRUE.parameters())
    np.testing.assert_allclose(again.forward([[10, 200, 30]]), TRUE.forward([[10, 200, 30]]))
    with pytest.raises(InputError, match="unknown display model"):
        fit_display_model(None, "no-such-model")
    with pytest.raises(InputError, match="cannot be fitted"):
        fit_display_model(None, "srgb")


def test_bad_inputs():
    with pytest.raises(InputError, match="0..255"):
        TRUE.forward([300, 0, 0])
    with pytest.raises(InputError, match="NaN"):
        TRUE.inverse([np.nan, 1, 1])
    with pytest.raises(InputError, match="last axis"):
        TRUE.forward([1, 2])
    with pytest.raises(InputError, match="singular"):
        GammaMatrixDisplay(gamma=[2.2] * 3, matrix=np.ones((3, 3)), white=[1, 1, 1])


def test_session_csv_round_trip_and_fit(tmp_path, rng):
    session = synthetic_session(TRUE, rng, noise=0.002)
    path = write_session_csv(session, tmp_path / "s.csv")
    again = read_session_csv(path)
    assert len(again) == len(session)
    np.testing.assert_allclose(again.XYZ, session.XYZ, rtol=1e-5)
    fitted = fit_display_model(again)
    np.testing.assert_allclose(fitted.gamma, TRUE.gamma, atol=0.02)


def test_session_csv_errors_name_line_and_fix(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("Kind,R,G,B,X,Y,Z\nwhite,255,255,255,95,100,108\nramp-r,5,0,0,abc,1,1\n")
    with pytest.raises(Exception, match=r"bad.csv, line 3: column 'X' holds 'abc'.*Fix"):
        read_session_csv(path)
    path.write_text("kind,r,g\nwhite,1,1\n")
    with pytest.raises(Exception, match=r"line 1: the header lacks"):
        read_session_csv(path)
    path.write_text("kind,r,g,b,X,Y,Z\npurple,1,1,1,1,1,1\n")
    with pytest.raises(Exception, match=r"line 2: unknown kind 'purple'"):
        read_session_csv(path)
