// Checks the patch shader's colour-space arithmetic (VrColourWorkbench.Patch.PatchColour) under mono.
//
// For every DAC 0..255 of each channel, in a Gamma and in a Linear colour-space project, it takes
// the value VrPatchServer hands to the shader (PatchColour.ShaderRgba), stores it as the shader
// would hold it (float32, or half when a platform runs the fragment stage in 16-bit floats), lets the
// GPU's output stage act on it (Linear: the sRGB encode of an sRGB render target, computed in
// double and in float32 arithmetic; Gamma: none, a UNORM target) and quantises to the 8-bit target
// (round to nearest). Every case must give back the DAC. It prints one line per case with the
// smallest distance to a rounding boundary (how far the arithmetic is from failing), and, to show
// that the check can fail, how many DACs a Linear project would get wrong if the shader wrote
// d / 255 as a Gamma project does. Exit status 0 when every case is exact, 1 otherwise.
using System;
using System.Globalization;
using VrColourWorkbench.Patch;

namespace VrColourWorkbench.MonoHost
{
    static class PatchColourCheck
    {
        /// <summary>float32 to IEEE half (round to nearest even) and back: what a 16-bit shader register holds.</summary>
        public static float ThroughHalf(float value)
        {
            int bits = BitConverter.ToInt32(BitConverter.GetBytes(value), 0);
            int sign = (bits >> 16) & 0x8000;
            int exponent = ((bits >> 23) & 0xff) - 127 + 15;
            int mantissa = bits & 0x7fffff;
            int half;
            if (((bits >> 23) & 0xff) == 0xff) half = sign | 0x7c00 | (mantissa != 0 ? 0x200 : 0);
            else if (exponent >= 0x1f) half = sign | 0x7c00;
            else if (exponent <= 0)
            {
                if (exponent < -10) half = sign;
                else
                {
                    mantissa |= 0x800000;
                    int shift = 14 - exponent;
                    int rounded = mantissa >> shift;
                    int remainder = mantissa & ((1 << shift) - 1);
                    int halfway = 1 << (shift - 1);
                    if (remainder > halfway || (remainder == halfway && (rounded & 1) != 0)) rounded++;
                    half = sign | rounded;
                }
            }
            else
            {
                int rounded = (exponent << 10) | (mantissa >> 13);
                int remainder = mantissa & 0x1fff;
                if (remainder > 0x1000 || (remainder == 0x1000 && (rounded & 1) != 0)) rounded++;
                half = sign | rounded;
            }
            // back to float
            int hs = (half & 0x8000) << 16, he = (half >> 10) & 0x1f, hm = half & 0x3ff;
            if (he == 0)
            {
                float sub = hm * (float)Math.Pow(2, -24);
                return hs != 0 ? -sub : sub;
            }
            if (he == 0x1f) return hm == 0 ? (hs != 0 ? float.NegativeInfinity : float.PositiveInfinity) : float.NaN;
            int fbits = hs | ((he - 15 + 127) << 23) | (hm << 13);
            return BitConverter.ToSingle(BitConverter.GetBytes(fbits), 0);
        }

        /// <summary>The sRGB encode in float32 arithmetic (every operation rounded to float).</summary>
        static float EncodeFloat32(float linear)
        {
            if (linear <= 0.0031308f) return linear * 12.92f;
            float power = (float)Math.Pow(linear, (float)(1.0 / 2.4));
            return 1.055f * power - 0.055f;
        }

        /// <summary>Float to 8-bit UNORM, round to nearest (as D3D/Vulkan convert), clamped.</summary>
        static int Quantise(double value, out double distanceToBoundary)
        {
            double scaled = value * 255.0;
            int dac = (int)Math.Floor(scaled + 0.5);
            distanceToBoundary = 0.5 - Math.Abs(scaled - dac);
            return Math.Max(0, Math.Min(255, dac));
        }

        static int Main(string[] args)
        {
            if (args.Length == 1 && args[0] == "--values")
            {
                // The shader values and their half-precision copies, for the workbench's test to compare
                // with numpy (float32 and float16): "dac linear float32 half" per line, values as "R".
                for (int dac = 0; dac <= 255; dac++)
                {
                    foreach (bool linearSpace in new[] { false, true })
                    {
                        float value = PatchColour.ShaderValue(dac, linearSpace);
                        Console.WriteLine(string.Format(CultureInfo.InvariantCulture, "{0} {1} {2:R} {3:R}",
                                                        dac, linearSpace ? 1 : 0, value, ThroughHalf(value)));
                    }
                }
                return 0;
            }
            bool allExact = true;
            var spaces = new[] { false, true };
            var precisions = new[] { "float32", "half" };
            var encodes = new[] { "double", "float32" };
            foreach (bool linear in spaces)
            {
                foreach (string precision in precisions)
                {
                    foreach (string encode in encodes)
                    {
                        if (!linear && encode == "float32") continue;  // a UNORM target applies no encode
                        int exact = 0, cases = 0;
                        double margin = 1.0;
                        string firstWrong = null;
                        for (int channel = 0; channel < 3; channel++)
                        {
                            for (int dac = 0; dac <= 255; dac++)
                            {
                                var rgb = new int[3];
                                rgb[channel] = dac;
                                float shader = PatchColour.ShaderRgba(rgb[0], rgb[1], rgb[2], linear)[channel];
                                if (precision == "half") shader = ThroughHalf(shader);
                                double stored = !linear ? shader
                                    : encode == "double" ? PatchColour.LinearToSrgb(shader) : EncodeFloat32(shader);
                                double distance;
                                int written = Quantise(stored, out distance);
                                cases++;
                                margin = Math.Min(margin, distance);
                                if (written == dac) exact++;
                                else if (firstWrong == null)
                                    firstWrong = "channel " + "RGB"[channel] + " DAC " + dac + " -> " + written;
                            }
                        }
                        allExact &= exact == cases;
                        Console.WriteLine(string.Format(CultureInfo.InvariantCulture,
                            "{0} project, shader {1}, encode {2}: {3}/{4} exact, smallest margin {5:F6} DAC{6}",
                            linear ? "Linear" : "Gamma", precision, linear ? encode : "none (UNORM)", exact, cases, margin,
                            firstWrong == null ? "" : "; first wrong: " + firstWrong));
                    }
                }
            }
            // The check can fail: a Linear project whose shader wrote d / 255 (the Gamma value).
            int wrong = 0;
            for (int dac = 0; dac <= 255; dac++)
            {
                double distance;
                if (Quantise(PatchColour.LinearToSrgb(PatchColour.ShaderValue(dac, false)), out distance) != dac) wrong++;
            }
            Console.WriteLine("control: a Linear project writing d/255 (no decode) gets " + wrong + "/256 DACs wrong");
            Console.WriteLine(allExact ? "all exact" : "NOT EXACT");
            return allExact ? 0 : 1;
        }
    }
}
