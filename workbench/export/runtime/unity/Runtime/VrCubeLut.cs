// A 3D LUT (.cube, Iridas/Resolve form: red fastest, input 0..1) on the CPU: the bundle's
// display_inverse.cube (engine sRGB output to HMD DAC/255). Sample() is the reference
// consumer's trilinear interpolation in float32; ToTexture3D() gives the same table as a
// Texture3D for a GPU step, sampled at TextureCoordinate(c) so that the GPU's texel-centre
// convention lands on the .cube's nodes; ApplyToPixels() is VrDisplayInverse's texture pre-pass.
using System;
using UnityEngine;

namespace VrColourWorkbench
{
    public sealed class VrCubeLut
    {
        /// <summary>Nodes per axis.</summary>
        public int Size { get; private set; }
        /// <summary>size^3 rgb values, r fastest then g then b (the .cube's row order).</summary>
        public float[] Table { get; private set; }

        public VrCubeLut(int size, Color[] rows)
        {
            if (size < 2 || rows == null || rows.Length != size * size * size)
                throw new BundleException(".cube: " + (rows == null ? 0 : rows.Length) + " rows for LUT_3D_SIZE " + size);
            Size = size;
            Table = new float[3 * rows.Length];
            for (int i = 0; i < rows.Length; ++i)
            {
                Table[3 * i] = rows[i].r;
                Table[3 * i + 1] = rows[i].g;
                Table[3 * i + 2] = rows[i].b;
            }
        }

        /// <summary>The table at sRGB-encoded (r, g, b) on 0..1, trilinear (clamped to 0..1): HMD DAC/255.</summary>
        public Color Sample(Color srgb)
        {
            float r, g, b;
            Trilinear(Table, Size, srgb.r, srgb.g, srgb.b, out r, out g, out b);
            return new Color(r, g, b, srgb.a);
        }

        /// <summary>
        /// The texture pre-pass: sRGB-authored 8-bit texels to the 8-bit DAC the headset must receive
        /// (each channel rounded to nearest, as the frame buffer's UNORM conversion does; alpha kept).
        /// </summary>
        public Color32[] ApplyToPixels(Color32[] srgb)
        {
            var output = new Color32[srgb.Length];
            for (int i = 0; i < srgb.Length; ++i)
            {
                float r, g, b;
                Trilinear(Table, Size, srgb[i].r / 255f, srgb[i].g / 255f, srgb[i].b / 255f, out r, out g, out b);
                output[i] = new Color32(ToByte(r), ToByte(g), ToByte(b), srgb[i].a);
            }
            return output;
        }

        /// <summary>value (0..1) to 8 bits: round(clamp(value) * 255), half to even.</summary>
        public static byte ToByte(float value)
        {
            float scaled = (value < 0f ? 0f : (value > 1f ? 1f : value)) * 255f;
            return (byte)Math.Round(scaled, MidpointRounding.ToEven);
        }

        /// <summary>The table as a Texture3D (RGBAFloat, bilinear filtering = trilinear in 3D, clamped).</summary>
        public Texture3D ToTexture3D()
        {
            var colours = new Color[Size * Size * Size];
            for (int i = 0; i < colours.Length; ++i) colours[i] = new Color(Table[3 * i], Table[3 * i + 1], Table[3 * i + 2], 1f);
            var texture = new Texture3D(Size, Size, Size, TextureFormat.RGBAFloat, false);
            texture.filterMode = FilterMode.Bilinear;  // trilinear across the three axes
            texture.wrapMode = TextureWrapMode.Clamp;
            texture.SetPixels(colours);                // red fastest, as the .cube: x = r, y = g, z = b
            texture.Apply(false);
            return texture;
        }

        /// <summary>Where a shader samples the Texture3D for input c (0..1): node i's texel centre is (i + 0.5) / size.</summary>
        public static float TextureCoordinate(float c, int size)
        {
            float clamped = c < 0f ? 0f : (c > 1f ? 1f : c);
            return (clamped * (size - 1) + 0.5f) / size;
        }

        /// <summary>
        /// Trilinear interpolation of a size^3 rgb table (r fastest) at (r, g, b) on 0..1, in float32
        /// in the reference consumer's order: position = clamp(c) * (n - 1), base = min(floor, n - 2),
        /// weights (1 - f, f) multiplied b, g, r, summed b outermost, r innermost.
        /// </summary>
        public static void Trilinear(float[] table, int n, float r, float g, float b, out float outR, out float outG, out float outB)
        {
            float n1 = (float)(n - 1);
            float pr = Clamp01(r) * n1, pg = Clamp01(g) * n1, pb = Clamp01(b) * n1;
            int r0 = Math.Min((int)Math.Floor(pr), n - 2), g0 = Math.Min((int)Math.Floor(pg), n - 2), b0 = Math.Min((int)Math.Floor(pb), n - 2);
            float fr = pr - r0, fg = pg - g0, fb = pb - b0;
            float sr = 0f, sg = 0f, sb = 0f;
            for (int db = 0; db < 2; ++db)
            {
                float wb = db == 1 ? fb : 1f - fb;
                for (int dg = 0; dg < 2; ++dg)
                {
                    float wg = dg == 1 ? fg : 1f - fg;
                    for (int dr = 0; dr < 2; ++dr)
                    {
                        float wr = dr == 1 ? fr : 1f - fr;
                        float w = wb * wg * wr;
                        int index = 3 * (((b0 + db) * n + (g0 + dg)) * n + (r0 + dr));
                        sr += w * table[index];
                        sg += w * table[index + 1];
                        sb += w * table[index + 2];
                    }
                }
            }
            outR = sr; outG = sg; outB = sb;
        }

        static float Clamp01(float value) { return value < 0f ? 0f : (value > 1f ? 1f : value); }
    }
}
