// Test driver run under mono: loads a bundle written by `export` with the Unity package's C#
// (VrColourBundle, VrCubeLut, VrLevel2Cpu and the components, against the UnityEngine test
// double) and prints, as one JSON object, every number the loader gives a scene, for
// tests/export/test_unity_mono.py to compare with the bundle's reference consumer.
//
//   mono LoaderDriver.exe BUNDLE POINTS.f32 PIXELS.rgba CUBE
//
// POINTS.f32: float32 little-endian r g b triples (the .cube is sampled there);
// PIXELS.rgba: 8-bit RGBA texels of a 64 x 64 sRGB-authored texture (the display-inverse pre-pass
// is applied to it through VrDisplayInverse); CUBE: the level-2 cube to relight.
// Float arrays are written as base64 of float32 little-endian (exact), bytes as base64.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Text;
using UnityEngine;
using VrColourWorkbench;

static class LoaderDriver
{
    static int Main(string[] args)
    {
        if (args.Length != 4)
        {
            Console.Error.WriteLine("usage: LoaderDriver.exe BUNDLE POINTS.f32 PIXELS.rgba CUBE");
            return 2;
        }
        string folder = Path.GetFullPath(args[0]);
        string cube = args[3];
        try
        {
            var output = new Json();
            output.Begin();
            VrColourBundle bundle = VrColourBundle.Load(folder);
            output.Key("lights"); Lights(bundle, output);
            output.Key("components"); Components(folder, cube, bundle, output);
            output.Key("cube"); Cube(bundle, ReadFloats(args[1]), output);
            output.Key("prepass"); Prepass(folder, File.ReadAllBytes(args[2]), output);
            output.Key("inverse"); Inverse(bundle, output);
            output.Key("level2"); Level2(bundle, cube, output);
            output.Key("bind"); Bind(bundle, cube, output);
            output.Key("log"); output.Strings(Debug.Messages.ToArray());
            output.End();
            Console.Out.Write(output.ToString());
            return 0;
        }
        catch (BundleException error)
        {
            Console.Error.WriteLine("error: " + error.Message);
            return 2;
        }
    }

    // level 1: the loader's Color for each light, and Color32 of it (what an 8-bit light colour is)
    static void Lights(VrColourBundle bundle, Json output)
    {
        output.Begin();
        foreach (string id in bundle.LightIds())
        {
            Color colour = bundle.LightColour(id);
            Color32 rgb8 = colour;
            output.Key(id);
            output.Begin();
            output.Key("rgb8"); output.Ints(new int[] { rgb8.r, rgb8.g, rgb8.b });
            output.Key("colour"); output.Floats(new[] { colour.r, colour.g, colour.b, colour.a });
            output.Key("white_luminance"); output.Floats(new[] { bundle.FindLight(id).XYZ[1] });
            output.End();
        }
        output.End();
    }

    // the components, driven as a scene would: a VrBundleLight switching sources, a VrLevel2Material
    // (CPU path) following it, in engine units and in physical units
    static void Components(string folder, string cube, VrColourBundle bundle, Json output)
    {
        output.Begin();
        foreach (var unit in new[] { VrBundleLight.IntensityUnit.EngineUnit, VrBundleLight.IntensityUnit.Physical })
        {
            var lamp = new GameObject("lamp " + unit);
            Light light = lamp.AddComponent<Light>();
            VrBundleLight bundleLight = lamp.AddComponent<VrBundleLight>();   // OnEnable without a folder: logs, as in Unity
            bundleLight.bundleFolder = folder;
            bundleLight.intensityUnit = unit;
            var board = new GameObject("board");
            MeshRenderer renderer = board.AddComponent<MeshRenderer>();
            renderer.sharedMaterial = new Material(Shader.Find("Standard"));
            VrLevel2Material level2 = board.AddComponent<VrLevel2Material>();
            level2.cube = cube;
            level2.path = VrLevel2Material.RelightPath.Cpu;
            level2.Follow(bundleLight);
            var events = new List<string>();
            bundleLight.SourceChanged += events.Add;
            output.Key(unit.ToString());
            output.Begin();
            foreach (string id in bundle.LightIds())
            {
                bundleLight.Select(id);
                Color32 rgb8 = light.color;
                var albedo = (Texture2D)renderer.sharedMaterial.GetTexture("_MainTex");
                output.Key(id);
                output.Begin();
                output.Key("rgb8"); output.Ints(new int[] { rgb8.r, rgb8.g, rgb8.b });
                output.Key("intensity"); output.Floats(new[] { light.intensity });
                output.Key("ev100"); output.Floats(new[] { bundleLight.FixedExposureEV100 });
                output.Key("relit_for"); output.String(level2.RelitFor);
                output.Key("unreachable"); output.Ints(new[] { level2.UnreachableTexels });
                output.Key("albedo_srgb"); output.Bool(albedo != null && !albedo.linearStorage);
                output.Key("albedo");   // null: the component could not relight (it logged why)
                if (albedo == null) output.String(null); else output.Bytes(albedo.GetRawTextureData());
                output.End();
            }
            bundleLight.SelectNext();   // wraps to the first source
            output.Key("next_after_last"); output.String(bundleLight.CurrentSource);
            level2.SetLevel2(false);    // the level switch: the fallback (none here) and no relight
            output.Key("level1_relit_for"); output.String(level2.RelitFor);
            output.Key("events"); output.Strings(events.ToArray());
            output.End();
        }
        output.End();
    }

    static void Cube(VrColourBundle bundle, float[] points, Json output)
    {
        VrCubeLut lut = bundle.LoadDisplayInverseLut();
        Texture3D texture = bundle.LoadDisplayInverseCube();
        int count = points.Length / 3;
        var sampled = new float[3 * count];
        var gpu = new float[3 * count];
        for (int i = 0; i < count; ++i)
        {
            Color value = lut.Sample(new Color(points[3 * i], points[3 * i + 1], points[3 * i + 2], 1f));
            sampled[3 * i] = value.r; sampled[3 * i + 1] = value.g; sampled[3 * i + 2] = value.b;
            Color filtered = texture.GetPixelBilinear(VrCubeLut.TextureCoordinate(points[3 * i], lut.Size),
                                                      VrCubeLut.TextureCoordinate(points[3 * i + 1], lut.Size),
                                                      VrCubeLut.TextureCoordinate(points[3 * i + 2], lut.Size));
            gpu[3 * i] = filtered.r; gpu[3 * i + 1] = filtered.g; gpu[3 * i + 2] = filtered.b;
        }
        var nodes = new float[3 * texture.width * texture.height * texture.depth];
        Color[] pixels = texture.GetPixels();
        for (int i = 0; i < pixels.Length; ++i) { nodes[3 * i] = pixels[i].r; nodes[3 * i + 1] = pixels[i].g; nodes[3 * i + 2] = pixels[i].b; }
        output.Begin();
        output.Key("size"); output.Ints(new[] { lut.Size, texture.width, texture.height, texture.depth });
        output.Key("table"); output.Floats(lut.Table);
        output.Key("texture3d_nodes"); output.Floats(nodes);
        output.Key("sample"); output.Floats(sampled);
        output.Key("texture3d_sample"); output.Floats(gpu);
        output.End();
    }

    // VrDisplayInverse on a renderer whose material holds a 64 x 64 sRGB texture
    static void Prepass(string folder, byte[] rgba, Json output)
    {
        var authored = new Texture2D(64, 64, TextureFormat.RGBA32, false, false);
        authored.SetPixelData(rgba, 0);
        authored.Apply(false);
        var panel = new GameObject("panel");
        MeshRenderer renderer = panel.AddComponent<MeshRenderer>();
        renderer.sharedMaterial = new Material(Shader.Find("Unlit/Texture"));
        renderer.sharedMaterial.mainTexture = authored;
        var inverse = panel.AddComponent<VrDisplayInverse>();   // OnEnable: no such bundle "headset" here, logs
        inverse.bundleFolder = folder;
        inverse.Apply();
        var shown = (Texture2D)renderer.sharedMaterial.mainTexture;
        output.Begin();
        output.Key("texels"); output.Bytes(shown.GetRawTextureData());
        output.Key("srgb"); output.Bool(!shown.linearStorage);
        output.Key("authored_kept"); output.Bool(inverse.Authored == authored);
        output.End();
    }

    // what the shader gets: the thresholds, cells and correction textures, and the CPU copies
    static void Inverse(VrColourBundle bundle, Json output)
    {
        output.Begin();
        output.Key("thresholds_texture"); output.Bytes(bundle.Thresholds.GetRawTextureData());
        output.Key("thresholds_size"); output.Ints(new[] { bundle.Thresholds.width, bundle.Thresholds.height });
        output.Key("cells_texture"); output.Bytes(bundle.Cells.GetRawTextureData());
        output.Key("cells_size"); output.Ints(new[] { bundle.Cells.width, bundle.Cells.height });
        output.Key("thresholds"); output.Floats(bundle.InverseThresholds);
        output.Key("cells"); output.Floats(bundle.InverseCells);
        output.Key("correction_size"); output.Ints(new[] { bundle.CorrectionSize });
        if (bundle.DriveCorrection != null)
        {
            Color[] pixels = bundle.DriveCorrection.GetPixels();
            var table = new float[3 * pixels.Length];
            for (int i = 0; i < pixels.Length; ++i) { table[3 * i] = pixels[i].r; table[3 * i + 1] = pixels[i].g; table[3 * i + 2] = pixels[i].b; }
            output.Key("correction_texture"); output.Floats(table);
            output.Key("correction"); output.Floats(bundle.CorrectionTable);
            output.Key("domain"); output.Floats(new[] { bundle.CorrectionDomain.x, bundle.CorrectionDomain.y });
        }
        output.End();
    }

    static void Level2(VrColourBundle bundle, string cube, Json output)
    {
        output.Begin();
        float[] planes = bundle.LoadCoefficientChannels(cube);
        output.Key("planes"); output.Floats(planes);
        foreach (string id in bundle.LightIds())
        {
            int unreachable;
            Color32[] texels = bundle.RelightCpuTexels(cube, id, out unreachable);
            Level2Lights table;
            Level2Light light = bundle.FindLevel2Light(cube, id, out table);
            int count = texels.Length;
            var drives = new float[3 * count];
            for (int t = 0; t < count; ++t)
                VrLevel2Cpu.Drive(planes, count, t, table.channels, light, out drives[3 * t], out drives[3 * t + 1], out drives[3 * t + 2]);
            var bytes = new byte[4 * count];
            for (int t = 0; t < count; ++t) { bytes[4 * t] = texels[t].r; bytes[4 * t + 1] = texels[t].g; bytes[4 * t + 2] = texels[t].b; bytes[4 * t + 3] = texels[t].a; }
            output.Key(id);
            output.Begin();
            output.Key("texels"); output.Bytes(bytes);
            output.Key("unreachable"); output.Ints(new[] { unreachable });
            output.Key("drive"); output.Floats(drives);
            output.End();
        }
        output.End();
    }

    // BindLevel2: the uniforms and textures the level-2 shader is given, and the coefficient layers
    static void Bind(VrColourBundle bundle, string cube, Json output)
    {
        output.Begin();
        Texture2DArray coefficients = bundle.LoadCoefficients(cube);
        var layers = new List<float>();
        for (int layer = 0; layer < coefficients.depth; ++layer)
            foreach (Color c in coefficients.TestDoubleTexels(layer))   // the loader made it unreadable, as in Unity
            { layers.Add(c.r); layers.Add(c.g); layers.Add(c.b); layers.Add(c.a); }
        output.Key("coefficient_layers"); output.Floats(layers.ToArray());
        output.Key("coefficient_size"); output.Ints(new[] { coefficients.width, coefficients.height, coefficients.depth });
        foreach (string id in bundle.LightIds())
        {
            var material = new Material(Shader.Find("Hidden/VrColourWorkbench/Level2Relight"));
            bundle.BindLevel2(material, cube, id);
            var rows = new List<float>();
            foreach (Vector4 row in material.GetVectorArray("_VrMatrixRows")) { rows.Add(row.x); rows.Add(row.y); rows.Add(row.z); rows.Add(row.w); }
            Vector4 offset = material.GetVector("_VrDriveOffset");
            Vector4 unreachable = material.GetVector("_VrUnreachableDac");
            output.Key(id);
            output.Begin();
            output.Key("matrix_rows"); output.Floats(rows.ToArray());
            output.Key("offset"); output.Floats(new[] { offset.x, offset.y, offset.z });
            output.Key("layers"); output.Ints(new[] { material.GetInt("_VrLayers"), material.GetInt("_VrCorrectionSize") });
            output.Key("unreachable_dac"); output.Floats(new[] { unreachable.x, unreachable.y, unreachable.z });
            output.Key("texel_table"); output.Bytes(((Texture2D)material.GetTexture("_VrTexelTable")).GetRawTextureData());
            output.Key("same_textures"); output.Bool(material.GetTexture("_VrCoefficients") == coefficients
                                                     && material.GetTexture("_VrThresholds") == bundle.Thresholds
                                                     && material.GetTexture("_VrCells") == bundle.Cells);
            output.End();
        }
        output.End();
    }

    static float[] ReadFloats(string path)
    {
        byte[] raw = File.ReadAllBytes(path);
        var values = new float[raw.Length / 4];
        Buffer.BlockCopy(raw, 0, values, 0, values.Length * 4);   // little-endian machines only (x86, ARM)
        return values;
    }

    sealed class Json
    {
        readonly StringBuilder text = new StringBuilder();
        bool first = true;
        void Comma() { if (!first) text.Append(','); first = false; }
        public void Begin() { Comma(); text.Append('{'); first = true; }
        public void End() { text.Append('}'); first = false; }
        public void Key(string key) { Comma(); Quote(key); text.Append(':'); first = true; }
        public void String(string value) { Comma(); if (value == null) text.Append("null"); else Quote(value); }
        public void Bool(bool value) { Comma(); text.Append(value ? "true" : "false"); }
        public void Ints(int[] values)
        {
            Comma(); text.Append('[');
            for (int i = 0; i < values.Length; ++i) { if (i > 0) text.Append(','); text.Append(values[i].ToString(CultureInfo.InvariantCulture)); }
            text.Append(']');
        }
        public void Strings(string[] values)
        {
            Comma(); text.Append('[');
            for (int i = 0; i < values.Length; ++i) { if (i > 0) text.Append(','); Quote(values[i]); }
            text.Append(']');
        }
        public void Floats(float[] values)
        {
            var raw = new byte[4 * values.Length];
            Buffer.BlockCopy(values, 0, raw, 0, raw.Length);
            Bytes(raw);
        }
        public void Bytes(byte[] values) { Comma(); Quote(Convert.ToBase64String(values)); }
        void Quote(string value)
        {
            text.Append('"');
            foreach (char c in value)
            {
                if (c == '"' || c == '\\') text.Append('\\').Append(c);
                else if (c < ' ') text.Append("\\u").Append(((int)c).ToString("x4"));
                else text.Append(c);
            }
            text.Append('"');
        }
        public override string ToString() { return text.ToString(); }
    }
}
