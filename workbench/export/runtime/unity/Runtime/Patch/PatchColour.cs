// What the patch shader must write so that the framebuffer holds exactly the DAC values.
//
// Plain C# (.NET Framework 4.x, C# 7.2), no UnityEngine: checked under mono by the workbench
// (instruments/unity_mono/PatchColourCheck.cs) for every DAC 0..255 of each channel, in both
// colour spaces, in float32 and in half precision.
//
// Gamma colour-space project: the eye buffer is an 8-bit UNORM target; nothing converts what the
//   fragment shader writes, which the GPU stores as round(v * 255). The shader writes d / 255.
// Linear colour-space project: the eye buffer is an 8-bit sRGB target (R8G8B8A8_SRGB); the GPU
//   encodes what the shader writes with the sRGB transfer function (IEC 61966-2-1) before
//   storing round(encode(v) * 255). The shader writes the linear value whose encoding is the
//   DAC: decode(d / 255), computed here in double and handed to the shader as a float.
// The values go to the material with Material.SetVector, which passes them unchanged; SetColor
// would convert a colour from gamma to linear in a Linear project by Unity's own arithmetic.
using System;

namespace VrColourWorkbench.Patch
{
    /// <summary>The colour-space arithmetic of the patch shader.</summary>
    public static class PatchColour
    {
        /// <summary>sRGB decoding (IEC 61966-2-1): encoded value 0..1 to linear 0..1.</summary>
        public static double SrgbToLinear(double encoded)
        {
            return encoded <= 0.04045 ? encoded / 12.92 : Math.Pow((encoded + 0.055) / 1.055, 2.4);
        }

        /// <summary>sRGB encoding (IEC 61966-2-1), as an sRGB render target applies it: linear 0..1 to encoded 0..1.</summary>
        public static double LinearToSrgb(double linear)
        {
            return linear <= 0.0031308 ? linear * 12.92 : 1.055 * Math.Pow(linear, 1.0 / 2.4) - 0.055;
        }

        /// <summary>The value the patch shader receives and writes for one channel's DAC value.</summary>
        /// <param name="dac">0..255.</param>
        /// <param name="linearColourSpace">The project's colour space is Linear (QualitySettings.activeColorSpace).</param>
        public static float ShaderValue(int dac, bool linearColourSpace)
        {
            if (dac < 0 || dac > 255) throw new ArgumentOutOfRangeException("dac", dac, "a DAC value is 0..255");
            double encoded = dac / 255.0;
            return (float)(linearColourSpace ? SrgbToLinear(encoded) : encoded);
        }

        /// <summary>The four shader values (alpha 1) for DAC values r, g, b.</summary>
        public static float[] ShaderRgba(int r, int g, int b, bool linearColourSpace)
        {
            return new[] { ShaderValue(r, linearColourSpace), ShaderValue(g, linearColourSpace), ShaderValue(b, linearColourSpace), 1f };
        }
    }
}
