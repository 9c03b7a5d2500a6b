"""The relight benchmark: the runtime bundle's level-2 method, at its K + S, on a paper-sized cube.

Procedure (:func:`benchmark_relight`):

1. the timed cube: ``size × size`` texels, 101 bands (380–780 nm, 4 nm, as
   the paper's cubes), of the 24 ColorChecker patches and the 15 NIST CQS
   samples mixed smoothly (:func:`~workbench.hyperspectral.synthetic.synthesize_cube`),
   float32;
2. K + S as a runtime bundle chooses them for this cube
   (:func:`workbench.export.level2_files.choose_cube_basis`: the fewest K
   basis coefficients + S precision channels whose runtime 8-bit texels equal
   the full band's on ≥ 99.9 % of held-out texels and ≥ 99.5 % of the
   library's materials, under every source timed), the channels encoded in
   float16, and the display inverse in the runtime's form (thresholds, cells;
   :func:`workbench.export.runtime_inverse.runtime_display_inverse`);
3. for each of D65, A, FL11 and the two-peak source: time a lighting change —
   the light's record (:func:`~workbench.export.level2_files.level2_light`:
   the C × 3 matrix and texel tables, the source's band weights cached as a
   runtime keeps them) then the per-texel kernel
   (:func:`~workbench.export.level2_files.relight_runtime_texture`, which also
   counts the texels the light cannot carry) — ``repeats`` times; the same
   arithmetic in NumPy (the reference consumer's) once; the naive full-band
   path (``(N, 101) @ (101, 3)`` float32, the display model's inverse, the
   texel arithmetic) ``full_band_repeats`` times; and compare the texels of
   the whole cube with the full band's.

Timings are wall-clock (``time.perf_counter``) on this machine with its
current load (the load average is reported beside them); the first kernel call
(numba compilation or cache load) is timed apart and excluded.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np

from workbench.colorimetry import DEFAULT_K, DEFAULT_OBSERVER
from workbench.display import DisplayModel, SRGBDisplay
from workbench.errors import InputError
from workbench.hyperspectral.basis import ACCURACY_SOURCES
from workbench.hyperspectral.materials import MATERIAL_SETS, material_reflectances
from workbench.hyperspectral.relight import relight_full_band
from workbench.hyperspectral.resampling import XYZ_band_weights
from workbench.hyperspectral.synthetic import PAPER_CUBE_WAVELENGTHS, synthesize_cube

__all__ = [
    "FRAME_BUDGET_MS",
    "GOAL_MS",
    "TIMED_MATERIALS",
    "RelightBenchmark",
    "benchmark_relight",
]

FRAME_BUDGET_MS = 1000.0 / 90.0
"""One frame at 90 Hz (11.1 ms): the budget for one relight."""

GOAL_MS = 5.0
"""What one relight of 1024² texels aims at on 2 cores (reading the K + S float16 channels
is the memory-bound floor, 2–3 ms)."""

TIMED_MATERIALS = ("colorchecker", "nist-cqs-vs")
"""The materials the timed cube is made of (:data:`~workbench.hyperspectral.materials.MATERIAL_SETS`)."""


@dataclass(frozen=True)
class RelightBenchmark:
    """Figures of one benchmark run (times in ms unless named ``_s``).

    ``ms_per_relight`` = the light's record (C × 3 matrix and tables, band
    weights cached) + the per-texel kernel, median over sources and repeats
    (``_min``/``_max`` their range); ``numpy_ms`` the same arithmetic in NumPy;
    ``full_band_ms`` the naive path (``full_band_product_ms``: its spectral
    product alone). ``identical``/``within_1_count``: per source, the share
    of the timed cube's texels equal to (within one count of) the full band's;
    ``held_out_identical``/``probe_identical``: the shares K + S were chosen
    on (held-out texels through the runtime's inverse; the library's
    materials). ``load_average``: the 1-minute load average before and after
    the timed runs.
    """

    size: int
    bands: int
    K: int
    split: int
    channels: int
    layers: int
    kernel: str
    threads: int
    cpus: int
    display: str
    ms_per_relight: float
    ms_per_relight_min: float
    ms_per_relight_max: float
    kernel_ms: float
    plan_ms: float
    numpy_ms: float
    full_band_ms: float
    full_band_product_ms: float
    speedup_vs_full: float
    identical: dict = field(default_factory=dict)
    within_1_count: dict = field(default_factory=dict)
    unreachable_texels: dict = field(default_factory=dict)
    held_out_identical: dict = field(default_factory=dict)
    probe_identical: dict = field(default_factory=dict)
    meets_target: bool = True
    materials: str = ", ".join(TIMED_MATERIALS)
    bytes_per_texel: int = 0
    kernel_GB_per_s: float = 0.0
    load_average: tuple = (0.0, 0.0)
    compile_s: float = 0.0
    synthesize_s: float = 0.0
    choose_s: float = 0.0
    frame_budget_ms: float = FRAME_BUDGET_MS
    goal_ms: float = GOAL_MS

    def to_json(self) -> dict:
        rounded = {}
        for key, value in self.__dict__.items():
            if isinstance(value, float):
                rounded[key] = round(value, 4)
            elif isinstance(value, dict):
                rounded[key] = {k: round(v, 6) for k, v in value.items()}
            elif isinstance(value, tuple):
                rounded[key] = [round(v, 2) for v in value]
            else:
                rounded[key] = value
        return rounded

    def summary(self) -> str:
        verdict = ("met" if self.ms_per_relight <= self.goal_ms else
                   "within the frame" if self.ms_per_relight <= self.frame_budget_ms else
                   "not met")
        lines = [
            f"relight benchmark: {self.size}×{self.size}×{self.bands} cube of "
            f"{_described(self.materials)}, display {self.display}",
            f"  runtime method: K = {self.K} + S = {self.split} float16 channels "
            f"({self.layers} RGBA16F layers, {self.bytes_per_texel} B/texel moved), as a bundle "
            f"chooses them{'' if self.meets_target else ' (closest tried: target not met)'}",
            f"  relight        {self.ms_per_relight:8.2f} ms (median; {self.ms_per_relight_min:.2f}"
            f"–{self.ms_per_relight_max:.2f}; kernel {self.kernel_ms:.2f} + light {self.plan_ms:.2f}; "
            f"{self.kernel_GB_per_s:.1f} GB/s; kernel {self.kernel}, {self.threads} "
            f"thread{'s' if self.threads != 1 else ''} on {self.cpus} CPUs, load average "
            f"{self.load_average[0]:.1f}–{self.load_average[1]:.1f})",
            f"                 goal ≤ {self.goal_ms:g} ms, frame ≤ {self.frame_budget_ms:.1f} ms: "
            f"{verdict}",
            f"  numpy          {self.numpy_ms:8.2f} ms   (the same arithmetic as the reference "
            "consumer)",
            f"  full band      {self.full_band_ms:8.2f} ms   speed-up × {self.speedup_vs_full:.1f} "
            f"(of which the (N, {self.bands}) @ ({self.bands}, 3) float32 product "
            f"{self.full_band_product_ms:.1f} ms)",
            "  8-bit texels equal to the full band's, whole cube (K + S chosen on: held-out "
            "texels / library materials):",
        ]
        for source, share in self.identical.items():
            lines.append(f"    {source:<16} {100 * share:7.3f} %   within 1 count "
                         f"{100 * self.within_1_count[source]:7.3f} %   ("
                         f"{100 * self.held_out_identical.get(source, float('nan')):.2f} / "
                         f"{100 * self.probe_identical.get(source, float('nan')):.2f} %)   "
                         f"unreachable {self.unreachable_texels[source]}")
        lines.append(f"  set-up: cube {self.synthesize_s:.1f} s, K + S chosen and encoded "
                     f"{self.choose_s:.1f} s, kernel compiled or loaded {self.compile_s:.1f} s")
        return "\n".join(lines)


def _described(material_sets: str) -> str:
    """``"a, b"`` material set ids → their descriptions."""
    names = [name.strip() for name in material_sets.split(",")]
    return " and ".join(MATERIAL_SETS[name].description if name in MATERIAL_SETS else name
                        for name in names)


def _median_ms(times: list[float]) -> float:
    return float(np.median(times) * 1e3)


def benchmark_relight(size: int = 1024, *, repeats: int = 20, full_band_repeats: int = 3,
                      display: DisplayModel | None = None, kernel: str = "auto",
                      threads: int | None = None, sources=ACCURACY_SOURCES, k: float = DEFAULT_K,
                      observer: str = DEFAULT_OBSERVER, seed: int = 0) -> RelightBenchmark:
    """Run the relight benchmark (module doc).

    Parameters
    ----------
    size : int
        Side of the timed cube in texels (1024: the paper's size; ≥ 16).
    repeats : int
        Timed relights per source.
    full_band_repeats : int
        Timed full-band runs per source.
    display : DisplayModel, optional
        Default: ideal sRGB.
    kernel : str
        ``"auto"``, ``"numba"`` or ``"numpy"``
        (:func:`~workbench.export.level2_files.runtime_level2_texels`).
    threads : int, optional
        Threads of the compiled kernel (default: every CPU).
    sources : sequence of str
        Sources K + S are chosen under, timed and scored.
    """
    if size < 16:
        raise InputError(f"--size {size}: the benchmark needs a cube of at least 16 × 16 texels")
    if repeats < 1 or full_band_repeats < 1:
        raise InputError("repeats must be at least 1")
    if threads is not None and threads < 1:
        raise InputError(f"--threads {threads}: at least 1")
    import numba

    from workbench.export.level2_files import (
        level2_light,
        relight_runtime_texture,
        resolve_runtime_kernel,
        runtime_level2_texels,
        runtime_texture,
    )
    from workbench.export.runtime_inverse import runtime_display_inverse
    from workbench.illuminants import get_illuminant

    display = display or SRGBDisplay()
    wavelengths = PAPER_CUBE_WAVELENGTHS
    started = time.perf_counter()
    spectra = np.vstack([material_reflectances(name, wavelengths) for name in TIMED_MATERIALS])
    cube = synthesize_cube(size, size, wavelengths=wavelengths, cell=max(4, size // 16),
                           seed=seed + 2, reflectances=spectra,
                           materials=" + ".join(MATERIAL_SETS[name].description
                                                for name in TIMED_MATERIALS))
    synthesize_s = time.perf_counter() - started

    illuminants = {source: get_illuminant(source) for source in sources}
    inverse = runtime_display_inverse(display)
    started = time.perf_counter()
    texture = runtime_texture(cube, display, list(illuminants.values()), inverse, k=k,
                              observer=observer, seed=seed)
    choose_s = time.perf_counter() - started
    planes = texture.planes
    choice = texture.choice

    Y_white = float(display.white_XYZ[1])
    weights = {source: XYZ_band_weights(illuminants[source].sd, cube.wavelengths, observer,
                                        k=k, Y_white=Y_white) for source in sources}
    out = np.empty((size, size, 3), dtype=np.uint8)
    first = next(iter(sources))
    started = time.perf_counter()
    relight_runtime_texture(texture, illuminants[first], display, inverse, k=k, kernel=kernel,
                            out=out, weights=weights[first], threads=threads)
    compile_s = time.perf_counter() - started
    kernel_name = resolve_runtime_kernel(inverse, kernel)

    relight_times, plan_times, kernel_times, full_times, numpy_times = [], [], [], [], []
    product_times = []
    identical, within, unreachable = {}, {}, {}
    texels = cube.texels()
    load_before = os.getloadavg()[0]
    for source in sources:
        for _ in range(repeats):
            t0 = time.perf_counter()
            light = level2_light(texture.basis, illuminants[source], display, inverse, k=k,
                                 split=texture.split, weights=weights[source])
            t1 = time.perf_counter()
            _, missed = runtime_level2_texels(planes, light, inverse, kernel=kernel,
                                              out=out.reshape(-1, 3), threads=threads)
            t2 = time.perf_counter()
            relight_times.append(t2 - t0)
            plan_times.append(t1 - t0)
            kernel_times.append(t2 - t1)
        unreachable[source] = missed
        t0 = time.perf_counter()
        runtime_level2_texels(planes, light, inverse, kernel="numpy")
        numpy_times.append(time.perf_counter() - t0)
        weights32 = weights[source].astype(np.float32)
        for _ in range(full_band_repeats):
            t0 = time.perf_counter()
            texels @ weights32
            product_times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            reference = relight_full_band(cube, illuminants[source], display, k=k,
                                          observer=observer, weights=weights[source])
            full_times.append(time.perf_counter() - t0)
        difference = np.abs(out.astype(np.int16) - reference.astype(np.int16)).max(axis=-1)
        identical[source] = float(np.mean(difference == 0))
        within[source] = float(np.mean(difference <= 1))
    load_after = os.getloadavg()[0]

    ms_per_relight = _median_ms(relight_times)
    kernel_ms = _median_ms(kernel_times)
    full_band_ms = _median_ms(full_times)
    channels = texture.components + texture.split
    bytes_per_texel = 2 * channels + 3
    return RelightBenchmark(
        size=size, bands=cube.bands, K=texture.components, split=texture.split,
        channels=channels, layers=-(-channels // 4), kernel=kernel_name,
        threads=(int(threads or numba.get_num_threads()) if kernel_name == "numba" else 1),
        cpus=_cpus(), display=display.describe(),
        ms_per_relight=ms_per_relight, ms_per_relight_min=float(np.min(relight_times) * 1e3),
        ms_per_relight_max=float(np.max(relight_times) * 1e3),
        kernel_ms=kernel_ms, plan_ms=_median_ms(plan_times), numpy_ms=_median_ms(numpy_times),
        full_band_ms=full_band_ms, full_band_product_ms=_median_ms(product_times),
        speedup_vs_full=full_band_ms / ms_per_relight,
        identical=identical, within_1_count=within, unreachable_texels=unreachable,
        held_out_identical=dict(choice.basis_identical), probe_identical=dict(choice.probe_identical),
        meets_target=choice.meets_target, bytes_per_texel=bytes_per_texel,
        kernel_GB_per_s=bytes_per_texel * size * size / (kernel_ms * 1e-3) / 1e9,
        load_average=(load_before, load_after), compile_s=compile_s,
        synthesize_s=synthesize_s, choose_s=choose_s)


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1
