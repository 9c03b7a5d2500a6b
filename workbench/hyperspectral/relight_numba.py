"""The fused level-2 relighting kernel, compiled with numba.

Per texel, in one pass over the float16 channel planes (a runtime bundle's
``K + S`` channels, or a basis's ``K`` coefficients):

1. ``drive = offset + Σ_k c_k · M_k`` — the channel vector times the C × 3
   matrix that folds basis × source weights × the display's XYZ → drive
   matrix (float32, one fused multiply-add per channel in channel order, as a
   shader's dot products; half → float conversion in hardware, F16C);
2. ``u = √clamp(drive, 0, 1)``;
3. the display inverse and the level-2 texel together, per channel, from a
   packed cell table (:meth:`~workbench.hyperspectral.channel_inverse.DacCells.texel_cells`):
   cell ``⌊u (L − 1)⌋`` holds at most one threshold, so one look-up and one
   comparison give the texel of the integer ``DAC_t`` — the same count of
   thresholds ``≤ u`` the runtime's shader makes;
4. the texels the light cannot carry (albedo clipped at 1, or a channel the
   light does not have) are counted: a channel's DAC reaches the light's
   unreachable level exactly when ``u`` reaches that level's threshold, one
   comparison per channel.

Texels go in blocks of :data:`BLOCK`: steps 1–2 are loops over the block that
the compiler vectorizes (AVX2/AVX-512), four channels per pass so that the
three drive accumulators are loaded and stored once per four channels; step 3
is a scalar loop per channel over the block (the compiler emits no vector
gathers for this CPU family). Compiled on first use and
cached on disk (``cache=True``), without the GIL.

Threads: the calling thread and up to ``threads − 1`` pool threads claim
chunks of :data:`CHUNK_TEXELS` texels from a shared counter until none is
left; the caller never waits for a pool thread that has not started (its task
is cancelled). Not numba's ``parallel=True``: on a machine whose cores other
jobs share, OpenMP's spinning workers took 3–4 × the single-thread time
(medians quantized to the 4 ms scheduler tick), and the workqueue layer aborts
the process when two threads relight at once (the GUI's workers may).

Bytes moved per texel: ``2 C`` read (float16 channels) + 3 written; the
cell tables (12 KB for 512 cells) stay in L1. On one core of the machine this
was written on (AMD EPYC, Zen 4) a 1024² texture of 30 channels takes about
4 ms for steps 1–2 and 3.5 ms for steps 3–4.

References
----------
Lam, S. K., Pitrou, A., Seibert, S. (2015), Numba: a LLVM-based Python JIT
compiler, Proc. LLVM-HPC '15. IEEE 754-2008 binary16 (half precision).
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["BLOCK", "CHUNK_TEXELS", "default_threads", "relight_level2_planes_numba"]

BLOCK = 8192
"""Texels per block: 3 float32 drives and 3 int32 cells per texel, 192 KB, stay in L2 (on a
1024² cube, 8192 took 15 % less time than 1024, the loops' set-up amortized; 16384 no less)."""

CHUNK_TEXELS = 8 * BLOCK
"""Texels a thread claims at a time (about half a millisecond of work)."""

_POOL_LOCK = threading.Lock()
_POOL: list = [None, 0]     # the executor and its number of threads

_FLAGS = {"contract"}
"""LLVM fast-math flags: fused multiply-add only. No reassociation (the channel sum keeps its
order), no approximate square root (``u`` is compared with thresholds bit for bit)."""


@intrinsic
def _half_bits_to_float32(typingctx, bits):
    """IEEE binary16 bits (uint16) → float32, as LLVM's ``fpext half`` (vcvtph2ps)."""
    signature = types.float32(types.uint16)

    def codegen(context, builder, sig, args):
        return builder.fpext(builder.bitcast(args[0], ir.HalfType()), ir.FloatType())

    return signature, codegen


@njit(fastmath=_FLAGS, inline="always", cache=True)
def _accumulate(planes, start, count, matrix, offset, drive_r, drive_g, drive_b):
    channels = planes.shape[0]
    offset_r, offset_g, offset_b = offset[0], offset[1], offset[2]
    for i in range(count):
        drive_r[i] = offset_r
        drive_g[i] = offset_g
        drive_b[i] = offset_b
    k = 0
    while k + 4 <= channels:          # four channels per pass over the block
        p0 = planes[k, start:start + count]
        p1 = planes[k + 1, start:start + count]
        p2 = planes[k + 2, start:start + count]
        p3 = planes[k + 3, start:start + count]
        r0, g0, b0 = matrix[k, 0], matrix[k, 1], matrix[k, 2]
        r1, g1, b1 = matrix[k + 1, 0], matrix[k + 1, 1], matrix[k + 1, 2]
        r2, g2, b2 = matrix[k + 2, 0], matrix[k + 2, 1], matrix[k + 2, 2]
        r3, g3, b3 = matrix[k + 3, 0], matrix[k + 3, 1], matrix[k + 3, 2]
        for i in range(count):
            c0 = _half_bits_to_float32(p0[i])
            c1 = _half_bits_to_float32(p1[i])
            c2 = _half_bits_to_float32(p2[i])
            c3 = _half_bits_to_float32(p3[i])
            drive_r[i] = drive_r[i] + c0 * r0 + c1 * r1 + c2 * r2 + c3 * r3
            drive_g[i] = drive_g[i] + c0 * g0 + c1 * g1 + c2 * g2 + c3 * g3
            drive_b[i] = drive_b[i] + c0 * b0 + c1 * b1 + c2 * b2 + c3 * b3
        k += 4
    while k < channels:
        plane = planes[k, start:start + count]
        m_r, m_g, m_b = matrix[k, 0], matrix[k, 1], matrix[k, 2]
        for i in range(count):
            c = _half_bits_to_float32(plane[i])
            drive_r[i] = drive_r[i] + c * m_r
            drive_g[i] = drive_g[i] + c * m_g
            drive_b[i] = drive_b[i] + c * m_b
        k += 1


@njit(fastmath=_FLAGS, inline="always", cache=True)
def _to_u(drive, count, scale, cell):
    for i in range(count):
        # + 0: −0 becomes +0, whose bits order with the thresholds' as unsigned integers
        u = np.sqrt(min(max(drive[i], np.float32(0.0)), np.float32(1.0))) + np.float32(0.0)
        drive[i] = u
        cell[i] = np.int32(u * scale)


@njit(fastmath=_FLAGS, inline="always", cache=True)
def _texel(u_bits, entry):
    """The packed cell entry's texel below or at/above its threshold (bits 32–39, 40–47)."""
    above = np.uint64(u_bits >= np.uint32(entry & np.uint64(0xFFFFFFFF)))
    return np.uint8((entry >> (np.uint64(32) + np.uint64(8) * above)) & np.uint64(0xFF))


@njit(fastmath=_FLAGS, nogil=True, cache=True)
def _relight_span(planes, matrix, offset, table, limits, out, first, last):
    """Texels ``first..last`` (module doc); returns how many the light cannot carry."""
    scale = np.float32(table.shape[1] - 1)
    drive_r = np.empty(BLOCK, np.float32)
    drive_g = np.empty(BLOCK, np.float32)
    drive_b = np.empty(BLOCK, np.float32)
    bits_r, bits_g, bits_b = drive_r.view(np.uint32), drive_g.view(np.uint32), drive_b.view(np.uint32)
    cell_r = np.empty(BLOCK, np.int32)
    cell_g = np.empty(BLOCK, np.int32)
    cell_b = np.empty(BLOCK, np.int32)
    table_r, table_g, table_b = table[0], table[1], table[2]
    limit_r, limit_g, limit_b = limits[0], limits[1], limits[2]
    missed = 0
    for start in range(first, last, BLOCK):
        count = min(BLOCK, last - start)
        _accumulate(planes, start, count, matrix, offset, drive_r, drive_g, drive_b)
        _to_u(drive_r, count, scale, cell_r)
        _to_u(drive_g, count, scale, cell_g)
        _to_u(drive_b, count, scale, cell_b)
        for i in range(count):
            missed += (drive_r[i] >= limit_r) | (drive_g[i] >= limit_g) | (drive_b[i] >= limit_b)
        block = out[start:start + count]
        for i in range(count):
            block[i, 0] = _texel(bits_r[i], table_r[cell_r[i]])
        for i in range(count):
            block[i, 1] = _texel(bits_g[i], table_g[cell_g[i]])
        for i in range(count):
            block[i, 2] = _texel(bits_b[i], table_b[cell_b[i]])
    return missed


def default_threads() -> int:
    """Threads a relight uses by default: numba's thread count (``NUMBA_NUM_THREADS``, else
    every CPU)."""
    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _pool(workers: int) -> ThreadPoolExecutor:
    with _POOL_LOCK:
        if _POOL[0] is None or _POOL[1] < workers:
            if _POOL[0] is not None:
                _POOL[0].shutdown(wait=False)
            _POOL[0], _POOL[1] = ThreadPoolExecutor(max_workers=workers,
                                                    thread_name_prefix="relight"), workers
        return _POOL[0]


def _shared(arguments: tuple, count: int, threads: int) -> int:
    """Run :func:`_relight_span` over ``count`` texels on the caller and ``threads − 1`` pool
    threads, each claiming :data:`CHUNK_TEXELS` at a time (module doc)."""
    lock = threading.Lock()
    claimed = [0]

    def work() -> int:
        missed = 0
        while True:
            with lock:
                first = claimed[0]
                claimed[0] = first + CHUNK_TEXELS
            if first >= count:
                return missed
            missed += _relight_span(*arguments, first, min(count, first + CHUNK_TEXELS))

    pool = _pool(threads - 1)
    helpers = [pool.submit(work) for _ in range(threads - 1)]
    missed = work()
    for helper in helpers:
        if not helper.cancel():         # started: it finishes the chunk it holds
            missed += helper.result()
    return int(missed)


def relight_level2_planes_numba(planes: np.ndarray, drive_matrix: np.ndarray,
                                drive_offset: np.ndarray, texel_cells: np.ndarray,
                                reach_limits: np.ndarray, out: np.ndarray, *,
                                threads: int | None = None) -> int:
    """Run the fused kernel (module doc) over flattened planes.

    Parameters
    ----------
    planes : ndarray (C, N), float16, C-contiguous
        Channel planes, texels flattened row-major.
    drive_matrix : ndarray (C, 3), float32
        ``drive = channels @ drive_matrix + drive_offset``.
    drive_offset : ndarray (3,), float32
    texel_cells : ndarray (3, L), uint64
        :meth:`~workbench.hyperspectral.channel_inverse.DacCells.texel_cells` of the
        display inverse's cells and the light's level-2 texel table.
    reach_limits : ndarray (3,), float32
        :meth:`~workbench.hyperspectral.channel_inverse.DacCells.reach_limits` of the
        light's unreachable levels: a texel is unreachable where any channel's ``u``
        reaches its limit.
    out : ndarray (N, 3), uint8, C-contiguous
        Receives the texels.
    threads : int, optional
        Threads to share the texels among (default :func:`default_threads`); 1 runs
        on the calling thread alone.

    Returns
    -------
    int
        The number of texels the light cannot carry.
    """
    bits = planes.view(np.uint16)
    arguments = (bits, np.ascontiguousarray(drive_matrix, dtype=np.float32),
                 np.ascontiguousarray(drive_offset, dtype=np.float32),
                 np.ascontiguousarray(texel_cells, dtype=np.uint64),
                 np.ascontiguousarray(reach_limits, dtype=np.float32), out)
    count = bits.shape[1]
    threads = default_threads() if threads is None else max(1, int(threads))
    threads = min(threads, -(-count // CHUNK_TEXELS))
    if threads <= 1:
        return int(_relight_span(*arguments, 0, count))
    return _shared(arguments, count, threads)
