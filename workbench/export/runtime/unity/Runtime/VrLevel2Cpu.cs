// Level 2 on the CPU, in C#: the arithmetic of Level2Relight.hlsl and of the bundle's
// reference_consumer.py, in float32, for platforms or moments where a GPU pass is not wanted
// (a Texture2D re-authored once per light change; no RenderTexture, no shader).
//
// Per texel: drive = matrix . channels + offset (the channels summed in order, then the offset,
// as the reference consumer writes it); where the bundle has a correction table,
// drive = trilinear(table, (clamp(drive, lo, hi) - lo) / (hi - lo)); u = sqrt(clamp(drive, 0, 1));
// DAC_c = how many of channel c's 255 thresholds are <= u_c (from the cell's lower bound, stepping
// up); texel_c = texel_table[c][DAC_c]; alpha 0 where any DAC_c >= unreachable_dac[c].
// The shader sums the same products in another order (offset first, four channels at a time),
// so on the GPU a texel whose u lies within float32 rounding of a threshold may differ by one count.
using System;
using UnityEngine;

namespace VrColourWorkbench
{
    public static class VrLevel2Cpu
    {
        /// <summary>The display inverse in the runtime's form (display_inverse.json and its correction table).</summary>
        public sealed class Inverse
        {
            public readonly float[] Thresholds;   // 3 x 255, row = channel
            public readonly int[] Cells;          // 3 x count: a lower bound of the DAC per cell of u
            public readonly int CellCount;
            public readonly float[] Correction;   // size^3 x rgb, r fastest; null: no correction
            public readonly int CorrectionSize;
            public readonly float Low, High;

            public Inverse(float[] thresholds, float[] cells, float[] correction, int correctionSize, float low, float high)
            {
                if (thresholds == null || thresholds.Length != 765)
                    throw new BundleException("display inverse: 765 thresholds expected");
                if (cells == null || cells.Length < 6 || cells.Length % 3 != 0)
                    throw new BundleException("display inverse: 3 rows of cells expected");
                Thresholds = thresholds;
                CellCount = cells.Length / 3;
                Cells = new int[cells.Length];
                for (int i = 0; i < cells.Length; ++i)
                {
                    if (!(cells[i] >= 0f && cells[i] <= 255f) || cells[i] != (float)Math.Floor(cells[i]))
                        throw new BundleException("display inverse: a cell is not a DAC level 0..255");
                    Cells[i] = (int)cells[i];
                }
                CorrectionSize = correction == null ? 0 : correctionSize;
                if (CorrectionSize > 0 && correction.Length != 3 * CorrectionSize * CorrectionSize * CorrectionSize)
                    throw new BundleException("display inverse: the correction table does not hold size^3 rgb values");
                Correction = correction;
                Low = low;
                High = high;
            }

            /// <summary>How many of the channel's thresholds are &lt;= u.</summary>
            public int DacLevel(int channel, float u)
            {
                int level = Cells[channel * CellCount + (int)(u * (float)(CellCount - 1))];
                while (level < 255 && Thresholds[channel * 255 + level] <= u) ++level;
                return level;
            }

            /// <summary>The corrected drive: the table sampled trilinearly at (clamp(drive, lo, hi) - lo) / (hi - lo).</summary>
            public void Correct(ref float r, ref float g, ref float b)
            {
                float range = High - Low;
                VrCubeLut.Trilinear(Correction, CorrectionSize, (r - Low) / range, (g - Low) / range, (b - Low) / range,
                                    out r, out g, out b);
            }
        }

        /// <summary>
        /// The level-2 texels of a cube under a light. <paramref name="planes"/>: [channel][texel]
        /// (VrColourBundle.LoadCoefficientChannels); texels come out in the planes' order, as Color32
        /// (alpha 0 where the light cannot carry the texel, else 255).
        /// </summary>
        public static Color32[] Relight(float[] planes, int width, int height, int channels, Level2Light light,
                                        Inverse inverse, out int unreachable)
        {
            int texels = width * height;
            if (planes == null || planes.Length != channels * texels)
                throw new BundleException("level 2: " + channels + " channels of " + texels + " texels expected");
            var output = new Color32[texels];
            unreachable = 0;
            for (int t = 0; t < texels; ++t)
            {
                float r, g, b;
                Drive(planes, texels, t, channels, light, out r, out g, out b);
                if (inverse.CorrectionSize > 0) inverse.Correct(ref r, ref g, ref b);
                int dr = inverse.DacLevel(0, Sqrt01(r));
                int dg = inverse.DacLevel(1, Sqrt01(g));
                int db = inverse.DacLevel(2, Sqrt01(b));
                bool cannot = dr >= light.unreachable_dac[0] || dg >= light.unreachable_dac[1] || db >= light.unreachable_dac[2];
                if (cannot) ++unreachable;
                output[t] = new Color32((byte)light.texel_table[dr], (byte)light.texel_table[256 + dg],
                                        (byte)light.texel_table[512 + db], cannot ? (byte)0 : (byte)255);
            }
            return output;
        }

        /// <summary>The drive of texel t before any correction: matrix . channels (summed in channel order) + offset.</summary>
        public static void Drive(float[] planes, int texels, int t, int channels, Level2Light light,
                                 out float r, out float g, out float b)
        {
            float[] matrix = light.matrix;   // 3 x C, row-major
            r = 0f; g = 0f; b = 0f;
            for (int c = 0; c < channels; ++c)
            {
                float value = planes[c * texels + t];
                r += value * matrix[c];
                g += value * matrix[channels + c];
                b += value * matrix[2 * channels + c];
            }
            r += light.offset[0];
            g += light.offset[1];
            b += light.offset[2];
        }

        /// <summary>sqrt(clamp(x, 0, 1)), correctly rounded in float32 (sqrt in double, then rounded once).</summary>
        public static float Sqrt01(float x)
        {
            float clamped = x < 0f ? 0f : (x > 1f ? 1f : x);
            return (float)Math.Sqrt(clamped);
        }

        /// <summary>An IEEE 754 binary16 value (little-endian bits) as float32, exactly.</summary>
        public static float HalfToSingle(ushort bits)
        {
            int sign = bits >> 15, exponent = (bits >> 10) & 31, mantissa = bits & 1023;
            int single;
            if (exponent == 31)
                single = (sign << 31) | (255 << 23) | (mantissa << 13);        // infinity, NaN
            else if (exponent != 0)
                single = (sign << 31) | ((exponent + 112) << 23) | (mantissa << 13);
            else if (mantissa == 0)
                single = sign << 31;                                          // signed zero
            else
            {
                int shift = 0;                                                // subnormal: normalise
                while ((mantissa & 1024) == 0) { mantissa <<= 1; ++shift; }
                single = (sign << 31) | ((113 - shift) << 23) | ((mantissa & 1023) << 13);
            }
            return BitConverter.ToSingle(BitConverter.GetBytes(single), 0);
        }
    }
}
