"""The fused level-2 relighting kernel, compiled with numba.

Per texel, in one pass over the float16 coefficient planes:

1. ``drive = offset + Σ_k c_k · M_k`` — the K-vector product with the K × 3
   matrix that folds basis × source weights × the display's XYZ → drive
   matrix (float32 accumulation; half → float conversion in hardware, F16C);
2. ``u = √clip(drive, 0, 1)``;
3. the display inverse as per-channel tables
   (:class:`~workbench.hyperspectral.channel_inverse.ChannelInverseLUT`): one
   look-up then a comparison or two give the integer ``DAC_t``;
4. the level-2 texel (sRGB decode, division by the light colour, clip, sRGB
   encode) from a 256-entry table per channel, written as uint8;
5. the texels the light cannot carry (albedo clipped at 1, or a channel the
   light does not have) are counted: a channel's DAC reaches the light's
   unreachable level ``v`` exactly when ``u ≥ thresholds[v]``, so this is one
   vectorized comparison per channel on the block, not per-texel branches.

Texels are processed in blocks of :data:`BLOCK` so that steps 1–2 run as
vector instructions over a block held in L1 cache, and the blocks are shared
among the CPU cores (``prange``). Compiled on first use and cached on disk
(``cache=True``).

Bytes moved per texel: ``2 K`` read (float16 coefficients) + 3 written; the
tables (≈ 50 KB) stay in cache.

References
----------
Lam, S. K., Pitrou, A., Seibert, S. (2015), Numba: a LLVM-based Python JIT
compiler, Proc. LLVM-HPC '15. IEEE 754-2008 binary16 (half precision).
"""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic

__all__ = ["BLOCK", "relight_level2_planes_numba"]

BLOCK = 512
"""Texels per block: 3 float32 accumulators + 3 int32 indices stay in L1 (12 KB)."""

_FAST = {"contract", "arcp", "nsz", "reassoc", "afn"}
"""LLVM fast-math flags: fused multiply-add and reassociation, but not ``nnan``/``ninf``
(the threshold tables end in +inf sentinels)."""


@intrinsic
def _half_bits_to_float32(typingctx, bits):
    """IEEE binary16 bits (uint16) → float32, as LLVM's ``fpext half`` (vcvtph2ps)."""
    signature = types.float32(types.uint16)

    def codegen(context, builder, sig, args):
        return builder.fpext(builder.bitcast(args[0], ir.HalfType()), ir.FloatType())

    return signature, codegen


@njit(fastmath=_FAST, inline="always", cache=True)
def _accumulate(planes, start, count, matrix, offset, drive_r, drive_g, drive_b):
    offset_r, offset_g, offset_b = offset[0], offset[1], offset[2]
    for i in range(count):
        drive_r[i] = offset_r
        drive_g[i] = offset_g
        drive_b[i] = offset_b
    for k in range(planes.shape[0]):
        plane = planes[k, start:start + count]
        m_r, m_g, m_b = matrix[k, 0], matrix[k, 1], matrix[k, 2]
        for i in range(count):
            c = _half_bits_to_float32(plane[i])
            drive_r[i] += c * m_r
            drive_g[i] += c * m_g
            drive_b[i] += c * m_b


@njit(fastmath=_FAST, inline="always", cache=True)
def _to_u(drive, count, scale, cell):
    for i in range(count):
        u = np.sqrt(min(max(drive[i], np.float32(0.0)), np.float32(1.0)))
        drive[i] = u
        cell[i] = np.int32(u * scale)


@njit(fastmath=_FAST, inline="always", cache=True)
def _texel(u, cell, cell_dac, thresholds, texel_table):
    dac = cell_dac[cell]
    while u >= thresholds[dac + 1]:
        dac += 1
    return texel_table[dac]


@njit(fastmath=_FAST, inline="always", cache=True)
def _count_unreachable(u_r, u_g, u_b, count, limit_r, limit_g, limit_b):
    missed = 0
    for i in range(count):
        missed += (u_r[i] >= limit_r) | (u_g[i] >= limit_g) | (u_b[i] >= limit_b)
    return missed


@njit(parallel=True, fastmath=_FAST, cache=True)
def _relight_kernel(planes, matrix, offset, cell_dac, thresholds, texel_table, unreachable_dac,
                    out, unreachable, chunks):
    count_all = planes.shape[1]
    step = ((count_all + chunks - 1) // chunks + BLOCK - 1) // BLOCK * BLOCK
    scale = np.float32(cell_dac.shape[1] - 1)
    # u from which each channel's DAC reaches the unreachable level (+inf: never).
    limit_r = thresholds[0, unreachable_dac[0]]
    limit_g = thresholds[1, unreachable_dac[1]]
    limit_b = thresholds[2, unreachable_dac[2]]
    for chunk in prange(chunks):
        drive_r = np.empty(BLOCK, np.float32)
        drive_g = np.empty(BLOCK, np.float32)
        drive_b = np.empty(BLOCK, np.float32)
        cell_r = np.empty(BLOCK, np.int32)
        cell_g = np.empty(BLOCK, np.int32)
        cell_b = np.empty(BLOCK, np.int32)
        dac_r, dac_g, dac_b = cell_dac[0], cell_dac[1], cell_dac[2]
        thr_r, thr_g, thr_b = thresholds[0], thresholds[1], thresholds[2]
        tex_r, tex_g, tex_b = texel_table[0], texel_table[1], texel_table[2]
        missed = 0
        for start in range(chunk * step, min(count_all, (chunk + 1) * step), BLOCK):
            count = min(BLOCK, count_all - start)
            _accumulate(planes, start, count, matrix, offset, drive_r, drive_g, drive_b)
            _to_u(drive_r, count, scale, cell_r)
            _to_u(drive_g, count, scale, cell_g)
            _to_u(drive_b, count, scale, cell_b)
            missed += _count_unreachable(drive_r, drive_g, drive_b, count,
                                         limit_r, limit_g, limit_b)
            block = out[start:start + count]
            for i in range(count):
                block[i, 0] = _texel(drive_r[i], cell_r[i], dac_r, thr_r, tex_r)
                block[i, 1] = _texel(drive_g[i], cell_g[i], dac_g, thr_g, tex_g)
                block[i, 2] = _texel(drive_b[i], cell_b[i], dac_b, thr_b, tex_b)
        unreachable[chunk] = missed


def relight_level2_planes_numba(planes: np.ndarray, drive_matrix: np.ndarray,
                                drive_offset: np.ndarray, cell_dac: np.ndarray,
                                thresholds: np.ndarray, texel_table: np.ndarray,
                                unreachable_dac: np.ndarray, out: np.ndarray) -> int:
    """Run the fused kernel (module doc) over flattened planes.

    Parameters
    ----------
    planes : ndarray (K, N), float16, C-contiguous
        Coefficient planes, texels flattened row-major.
    drive_matrix : ndarray (K, 3), float32
        Basis × source weights × display XYZ → drive.
    drive_offset : ndarray (3,), float32
        The mean reflectance's drive (plus the display's drive offset).
    cell_dac, thresholds : ndarray
        :class:`~workbench.hyperspectral.channel_inverse.ChannelInverseLUT` tables.
    texel_table : ndarray (3, 256), uint8
        :func:`~workbench.hyperspectral.level2_texels.level2_texel_table`.
    unreachable_dac : ndarray (3,), int32
        :func:`~workbench.hyperspectral.level2_texels.level2_unreachable_dac`.
    out : ndarray (N, 3), uint8, C-contiguous
        Receives the texels.

    Returns
    -------
    int
        The number of texels the light cannot carry.
    """
    chunks = 4 * numba.get_num_threads()  # a few blocks of texels per thread, to balance load
    unreachable = np.zeros(chunks, dtype=np.int64)
    _relight_kernel(planes.view(np.uint16), drive_matrix, drive_offset, cell_dac, thresholds,
                    texel_table, np.asarray(unreachable_dac, dtype=np.int32), out, unreachable,
                    chunks)
    return int(unreachable.sum())
