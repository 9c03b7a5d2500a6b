// Unity loader of a VR colour workbench runtime bundle (C# 7.2; Unity 2021.3 or newer).
//
//   var bundle = VrColourBundle.Load(Path.Combine(Application.streamingAssetsPath, "headset"));
//   sceneLight.color = bundle.LightColour("cie-d65");                       // level 1
//   albedo = bundle.Relight(relightMaterial, "paintings", "cie-d65", albedo); // level 2, GPU
//   albedo = bundle.RelightCpu("paintings", "cie-d65", albedo);               // level 2, CPU
//
// relightMaterial uses the shader "Hidden/VrColourWorkbench/Level2Relight"
// (Shaders/VrLevel2Relight.shader + Shaders/Level2Relight.hlsl); the returned
// Texture2D is sRGB (linear: false) and goes in the albedo slot of the object's
// material. The components VrBundleLight, VrLevel2Material and VrDisplayInverse
// do this from the inspector.
//
// Builds the Texture2DArray of a cube's coefficients (RGBAHalf), the display
// inverse .cube as a Texture3D (RGBAFloat, bilinear = trilinear in 3D) for a
// colour-grading step, and the level-2 tables; keeps the same data on the CPU
// for RelightCpu (VrLevel2Cpu) and VrCubeLut. Reads only data, never code.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using UnityEngine;

namespace VrColourWorkbench
{
    [Serializable] public class BundleCube { public string name; public string folder; public int width; public int height; public int components; public int split; public int channels; public int layers; }
    [Serializable] public class BundleManifest { public string format; public int format_version; public string profile; public string runtime_colour_space; public string display_inverse_cube; public string display_inverse; public string lights_file; public string[] lights; public BundleCube[] cubes; }
    [Serializable] public class LightEntry { public string id; public string name; public int[] rgb8; public float[] linear; public float[] XYZ; public float Rf; public float CCT; public bool in_gamut; }
    [Serializable] public class LightTable { public string format; public int format_version; public LightEntry[] lights; }
    [Serializable] public class Correction { public int size; public float[] domain; public string file; }
    [Serializable] public class DisplayInverse { public string format; public int format_version; public float[] thresholds; public float[] cells; public Correction correction; }
    [Serializable] public class CoefficientHeader { public string format; public int format_version; public string file; public int width; public int height; public int components; public int channels; public int layers; public int bytes; }
    [Serializable] public class Level2Light { public string id; public float[] matrix; public float[] offset; public int[] light_rgb8; public int[] texel_table; public int[] unreachable_dac; }
    [Serializable] public class Level2Lights { public int components; public int channels; public int layers; public Level2Light[] lights; }

    public sealed class BundleException : Exception
    {
        public BundleException(string message) : base(message) { }
    }

    public sealed class VrColourBundle
    {
        public const int SupportedFormatVersion = 1;
        public const int MaxLayers = 16;

        public string Directory { get; private set; }
        public BundleManifest Manifest { get; private set; }
        public LightTable Lights { get; private set; }
        public Texture2D Thresholds { get; private set; }
        public Texture2D Cells { get; private set; }
        public Texture3D DriveCorrection { get; private set; }
        public Vector4 CorrectionDomain { get; private set; }
        public int CorrectionSize { get; private set; }
        /// <summary>The display inverse as read, for the CPU path: 3 x 255 thresholds, 3 rows of cells, the correction table (r fastest rgb, or null).</summary>
        public float[] InverseThresholds { get; private set; }
        public float[] InverseCells { get; private set; }
        public float[] CorrectionTable { get; private set; }
        readonly Dictionary<string, Texture2DArray> coefficients = new Dictionary<string, Texture2DArray>();
        readonly Dictionary<string, Texture2D> texelTables = new Dictionary<string, Texture2D>();
        readonly Dictionary<string, float[]> channels = new Dictionary<string, float[]>();
        readonly Dictionary<string, Level2Lights> level2Lights = new Dictionary<string, Level2Lights>();
        VrCubeLut displayInverseLut;
        static readonly Dictionary<string, VrColourBundle> shared = new Dictionary<string, VrColourBundle>();

        VrColourBundle() { }

        /// <summary>A folder relative to StreamingAssets (or an absolute one) as a path.</summary>
        public static string ResolveFolder(string folder)
        {
            if (string.IsNullOrEmpty(folder)) throw new BundleException("no bundle folder given: name a folder under StreamingAssets");
            return Path.IsPathRooted(folder) ? folder : Path.Combine(Application.streamingAssetsPath, folder);
        }

        /// <summary>The bundle of a folder (see ResolveFolder), loaded once and shared by every component that names it.</summary>
        public static VrColourBundle Shared(string folder)
        {
            string directory = ResolveFolder(folder);
            VrColourBundle bundle;
            if (!shared.TryGetValue(directory, out bundle))
            {
                bundle = Load(directory);
                shared[directory] = bundle;
            }
            return bundle;
        }

        /// <summary>Forgets the shared bundles (after a new export into the same folder).</summary>
        public static void ForgetShared() { shared.Clear(); }

        public static VrColourBundle Load(string directory)
        {
            var bundle = new VrColourBundle { Directory = directory };
            bundle.Manifest = ReadJson<BundleManifest>(directory, "bundle.json");
            if (bundle.Manifest.format != "vr-colour-workbench-bundle")
                throw new BundleException(directory + ": not a VR colour workbench bundle");
            if (bundle.Manifest.format_version > SupportedFormatVersion)
                throw new BundleException(directory + ": bundle format_version " + bundle.Manifest.format_version
                    + " is newer than this loader supports (" + SupportedFormatVersion + ")");
            bundle.Lights = ReadJson<LightTable>(directory, bundle.Manifest.lights_file);
            var inverse = ReadJson<DisplayInverse>(directory, bundle.Manifest.display_inverse);
            if (inverse.thresholds == null || inverse.thresholds.Length != 3 * 255)
                throw new BundleException(directory + ": display_inverse.json needs 765 thresholds");
            bundle.Thresholds = FloatTable(inverse.thresholds, 255);
            bundle.InverseThresholds = inverse.thresholds;
            if (inverse.cells == null || inverse.cells.Length % 3 != 0 || inverse.cells.Length == 0)
                throw new BundleException(directory + ": display_inverse.json needs 3 rows of cells");
            bundle.Cells = FloatTable(inverse.cells, inverse.cells.Length / 3);
            bundle.InverseCells = inverse.cells;
            bundle.CorrectionSize = inverse.correction == null ? 0 : inverse.correction.size;
            if (bundle.CorrectionSize > 0)
            {
                int n = bundle.CorrectionSize;
                if (n < 2 || n > 257 || inverse.correction.domain == null || inverse.correction.domain.Length != 2)
                    throw new BundleException(directory + ": display_inverse.json correction needs a size of 2..257 and a domain of 2 numbers");
                byte[] raw = ReadBytes(directory, inverse.correction.file, n * n * n * 3 * 4);
                var colours = new Color[n * n * n];
                var table = new float[3 * n * n * n];
                for (int i = 0; i < table.Length; ++i) table[i] = ReadSingle(raw, 4 * i);
                for (int i = 0; i < colours.Length; ++i)
                    colours[i] = new Color(table[3 * i], table[3 * i + 1], table[3 * i + 2], 1f);
                bundle.CorrectionTable = table;
                var texture = new Texture3D(n, n, n, TextureFormat.RGBAFloat, false);
                texture.filterMode = FilterMode.Point;
                texture.wrapMode = TextureWrapMode.Clamp;
                texture.SetPixels(colours);
                texture.Apply(false);
                bundle.DriveCorrection = texture;
                bundle.CorrectionDomain = new Vector4(inverse.correction.domain[0], inverse.correction.domain[1], 0f, 0f);
            }
            return bundle;
        }

        /// <summary>Level 1: the engine light colour (sRGB-encoded, as Light.color takes it).</summary>
        public Color LightColour(string id)
        {
            LightEntry light = FindLight(id);
            return new Color32((byte)light.rgb8[0], (byte)light.rgb8[1], (byte)light.rgb8[2], 255);
        }

        /// <summary>Level 1: the lights.json record of a source (rgb8, linear, XYZ of the white diffuser, ...).</summary>
        public LightEntry FindLight(string id)
        {
            if (Lights.lights != null)
                foreach (var light in Lights.lights)
                    if (light.id == id)
                    {
                        if (light.rgb8 == null || light.rgb8.Length != 3 || light.XYZ == null || light.XYZ.Length != 3)
                            throw new BundleException("lights.json: light '" + id + "' needs rgb8 and XYZ of 3 numbers");
                        foreach (int value in light.rgb8)
                            if (value < 0 || value > 255) throw new BundleException("lights.json: light '" + id + "' has rgb8 outside 0..255");
                        return light;
                    }
            throw new BundleException("no light '" + id + "' in the bundle");
        }

        /// <summary>The source ids of lights.json, in the bundle's order.</summary>
        public string[] LightIds()
        {
            var ids = new string[Lights.lights == null ? 0 : Lights.lights.Length];
            for (int i = 0; i < ids.Length; ++i) ids[i] = Lights.lights[i].id;
            return ids;
        }

        /// <summary>The names of the bundle's level-2 cubes.</summary>
        public string[] CubeNames()
        {
            var names = new string[Manifest.cubes == null ? 0 : Manifest.cubes.Length];
            for (int i = 0; i < names.Length; ++i) names[i] = Manifest.cubes[i].name;
            return names;
        }

        /// <summary>The display inverse .cube (engine sRGB output to HMD DAC/255) as a Texture3D.</summary>
        public Texture3D LoadDisplayInverseCube()
        {
            return LoadDisplayInverseLut().ToTexture3D();
        }

        /// <summary>The display inverse .cube on the CPU (VrCubeLut: Sample, ApplyToPixels, ToTexture3D); read once.</summary>
        public VrCubeLut LoadDisplayInverseLut()
        {
            if (displayInverseLut != null) return displayInverseLut;
            string path = Path.Combine(Directory, Manifest.display_inverse_cube);
            int size = 0;
            var colours = new List<Color>();
            foreach (string line in File.ReadAllLines(path))
            {
                string text = line.Trim();
                if (text.Length == 0 || text.StartsWith("#") || text.StartsWith("TITLE")) continue;
                string[] parts = text.Split(new[] { ' ', '\t' }, StringSplitOptions.RemoveEmptyEntries);
                try
                {
                    if (parts[0] == "LUT_3D_SIZE") { size = int.Parse(parts[1], CultureInfo.InvariantCulture); continue; }
                    if (parts.Length != 3) throw new FormatException();
                    colours.Add(new Color(float.Parse(parts[0], CultureInfo.InvariantCulture),
                                          float.Parse(parts[1], CultureInfo.InvariantCulture),
                                          float.Parse(parts[2], CultureInfo.InvariantCulture), 1f));
                }
                catch (Exception error) when (error is FormatException || error is OverflowException
                                              || error is IndexOutOfRangeException)
                {
                    throw new BundleException(path + ": '" + text + "' is not a size or a row of r g b");
                }
            }
            if (size < 2 || colours.Count != size * size * size)
                throw new BundleException(path + ": not a complete .cube");
            displayInverseLut = new VrCubeLut(size, colours.ToArray());
            return displayInverseLut;
        }

        /// <summary>Level 2: the coefficient layers of a cube as a Texture2DArray (RGBAHalf, rows bottom first).</summary>
        public Texture2DArray LoadCoefficients(string cube)
        {
            Texture2DArray cached;
            if (coefficients.TryGetValue(cube, out cached)) return cached;
            BundleCube entry = FindCube(cube);
            var header = ReadJson<CoefficientHeader>(Directory, entry.folder + "/coefficients.json");
            if (header.layers != (header.channels + 3) / 4 || header.layers > MaxLayers)
                throw new BundleException(cube + ": inconsistent coefficient header");
            int rowBytes = header.width * 4 * 2;
            int layerBytes = rowBytes * header.height;
            byte[] raw = ReadBytes(Directory, entry.folder + "/" + header.file, layerBytes * header.layers);
            var texture = new Texture2DArray(header.width, header.height, header.layers, TextureFormat.RGBAHalf, false, true);
            texture.filterMode = FilterMode.Point;
            texture.wrapMode = TextureWrapMode.Clamp;
            var layer = new byte[layerBytes];
            for (int l = 0; l < header.layers; ++l)
            {
                for (int row = 0; row < header.height; ++row)  // the file is top row first; Unity is bottom first
                    Buffer.BlockCopy(raw, l * layerBytes + row * rowBytes, layer, (header.height - 1 - row) * rowBytes, rowBytes);
                texture.SetPixelData(layer, 0, l);
            }
            texture.Apply(false, true);
            coefficients[cube] = texture;
            return texture;
        }

        /// <summary>Sets every input of Level2Relight.hlsl on a material for one cube and one light.</summary>
        public void BindLevel2(Material material, string cube, string lightId)
        {
            Level2Lights table;
            Level2Light light = FindLevel2Light(cube, lightId, out table);
            int channels = table.channels;
            var rows = new Vector4[3 * MaxLayers];
            for (int layer = 0; layer < table.layers; ++layer)
                for (int output = 0; output < 3; ++output)
                {
                    var row = new Vector4();
                    for (int i = 0; i < 4; ++i)
                    {
                        int channel = 4 * layer + i;
                        row[i] = channel < channels ? light.matrix[output * channels + channel] : 0f;
                    }
                    rows[3 * layer + output] = row;
                }
            Texture2D texelTable;   // one texture per cube and light, not one per call
            if (!texelTables.TryGetValue(cube + "\n" + lightId, out texelTable))
            {
                var texels = new float[768];
                for (int i = 0; i < 768; ++i) texels[i] = light.texel_table[i];
                texelTable = FloatTable(texels, 256);
                texelTables[cube + "\n" + lightId] = texelTable;
            }
            material.SetTexture("_VrCoefficients", LoadCoefficients(cube));
            material.SetTexture("_VrThresholds", Thresholds);
            material.SetTexture("_VrCells", Cells);
            material.SetTexture("_VrTexelTable", texelTable);
            if (DriveCorrection != null) material.SetTexture("_VrDriveCorrection", DriveCorrection);
            material.SetVectorArray("_VrMatrixRows", rows);
            material.SetVector("_VrDriveOffset", new Vector4(light.offset[0], light.offset[1], light.offset[2], 0f));
            material.SetVector("_VrCorrectionDomain", CorrectionDomain);
            material.SetInt("_VrLayers", table.layers);
            material.SetInt("_VrCorrectionSize", CorrectionSize);
            material.SetVector("_VrUnreachableDac", new Vector4(light.unreachable_dac[0], light.unreachable_dac[1], light.unreachable_dac[2], 0f));
        }

        /// <summary>Level 2: relights a cube under a light into an sRGB Texture2D (created if null).</summary>
        public Texture2D Relight(Material material, string cube, string lightId, Texture2D albedo)
        {
            BundleCube entry = FindCube(cube);
            BindLevel2(material, cube, lightId);
            var target = new RenderTexture(entry.width, entry.height, 0, RenderTextureFormat.ARGB32,
                                           RenderTextureReadWrite.Linear);
            target.Create();
            RenderTexture previous = RenderTexture.active;
            Graphics.SetRenderTarget(target);
            material.SetPass(0);
            Graphics.DrawProceduralNow(MeshTopology.Triangles, 3);
            RenderTexture.active = previous;
            if (albedo == null)
                albedo = new Texture2D(entry.width, entry.height, TextureFormat.RGBA32, false, false);
            Graphics.CopyTexture(target, albedo);  // the same bytes, now sampled as sRGB
            target.Release();
            return albedo;
        }

        /// <summary>Level 2 on the CPU: the same arithmetic as Level2Relight.hlsl (VrLevel2Cpu), into an sRGB Texture2D (created if null).</summary>
        public Texture2D RelightCpu(string cube, string lightId, Texture2D albedo)
        {
            int unreachable;
            return RelightCpu(cube, lightId, albedo, out unreachable);
        }

        /// <summary>RelightCpu, and how many texels the light cannot carry (alpha 0).</summary>
        public Texture2D RelightCpu(string cube, string lightId, Texture2D albedo, out int unreachable)
        {
            BundleCube entry = FindCube(cube);
            Color32[] texels = RelightCpuTexels(cube, lightId, out unreachable);
            if (albedo == null || albedo.width != entry.width || albedo.height != entry.height)
                albedo = new Texture2D(entry.width, entry.height, TextureFormat.RGBA32, false, false);
            albedo.filterMode = FilterMode.Point;
            albedo.wrapMode = TextureWrapMode.Clamp;
            albedo.SetPixels32(texels);
            albedo.Apply(false);
            return albedo;
        }

        /// <summary>Level 2 on the CPU: the texels (rows bottom first, as Texture2D.SetPixels32 takes them; alpha 0 where the light cannot carry the texel).</summary>
        public Color32[] RelightCpuTexels(string cube, string lightId, out int unreachable)
        {
            Level2Lights table;
            Level2Light light = FindLevel2Light(cube, lightId, out table);
            BundleCube entry = FindCube(cube);
            float[] planes = LoadCoefficientChannels(cube);
            var inverse = new VrLevel2Cpu.Inverse(InverseThresholds, InverseCells, CorrectionTable, CorrectionSize,
                                                  CorrectionDomain.x, CorrectionDomain.y);
            return VrLevel2Cpu.Relight(planes, entry.width, entry.height, table.channels, light, inverse, out unreachable);
        }

        /// <summary>Level 2 on the CPU: a cube's coefficient channels as floats, [channel][row, bottom first][column].</summary>
        public float[] LoadCoefficientChannels(string cube)
        {
            float[] planes;
            if (channels.TryGetValue(cube, out planes)) return planes;
            BundleCube entry = FindCube(cube);
            var header = ReadJson<CoefficientHeader>(Directory, entry.folder + "/coefficients.json");
            if (header.layers != (header.channels + 3) / 4 || header.layers > MaxLayers || header.width != entry.width
                || header.height != entry.height || header.width < 1 || header.height < 1)
                throw new BundleException(cube + ": inconsistent coefficient header");
            int texels = header.width * header.height;
            byte[] raw = ReadBytes(Directory, entry.folder + "/" + header.file, texels * 8 * header.layers);
            planes = new float[header.channels * texels];
            for (int layer = 0; layer < header.layers; ++layer)
                for (int row = 0; row < header.height; ++row)   // the file is top row first; Unity is bottom first
                    for (int column = 0; column < header.width; ++column)
                    {
                        int source = ((layer * header.height + row) * header.width + column) * 8;
                        int texel = (header.height - 1 - row) * header.width + column;
                        for (int i = 0; i < 4; ++i)
                        {
                            int channel = 4 * layer + i;
                            if (channel < header.channels)
                                planes[channel * texels + texel] = VrLevel2Cpu.HalfToSingle((ushort)(raw[source + 2 * i] | (raw[source + 2 * i + 1] << 8)));
                        }
                    }
            channels[cube] = planes;
            return planes;
        }

        /// <summary>A level-2 light record of a cube (matrix, offset, texel table, unreachable levels), checked.</summary>
        public Level2Light FindLevel2Light(string cube, string lightId, out Level2Lights table)
        {
            BundleCube entry = FindCube(cube);
            if (!level2Lights.TryGetValue(cube, out table))
            {
                table = ReadJson<Level2Lights>(Directory, entry.folder + "/lights.json");
                level2Lights[cube] = table;
            }
            Level2Light light = null;
            if (table.lights != null)
                foreach (var candidate in table.lights) if (candidate.id == lightId) light = candidate;
            if (light == null) throw new BundleException(cube + ": no level-2 light '" + lightId + "'");
            if (table.channels < 1 || table.layers != (table.channels + 3) / 4 || table.layers > MaxLayers
                || light.matrix == null || light.matrix.Length != 3 * table.channels
                || light.offset == null || light.offset.Length != 3
                || light.texel_table == null || light.texel_table.Length != 768
                || light.unreachable_dac == null || light.unreachable_dac.Length != 3)
                throw new BundleException(cube + ": malformed level-2 light '" + lightId + "'");
            return light;
        }

        BundleCube FindCube(string cube)
        {
            if (Manifest.cubes != null)
                foreach (var entry in Manifest.cubes) if (entry.name == cube) return entry;
            throw new BundleException("no level-2 cube '" + cube + "' in the bundle");
        }

        static Texture2D FloatTable(float[] values, int width)
        {
            var texture = new Texture2D(width, 3, TextureFormat.RFloat, false, true);
            texture.filterMode = FilterMode.Point;
            texture.wrapMode = TextureWrapMode.Clamp;
            texture.SetPixelData(values, 0);
            texture.Apply(false);
            return texture;
        }

        static T ReadJson<T>(string directory, string name)
        {
            string path = Path.Combine(directory, name);
            if (!File.Exists(path)) throw new BundleException(path + ": missing from the bundle");
            T value;
            try { value = JsonUtility.FromJson<T>(File.ReadAllText(path)); }
            catch (ArgumentException) { throw new BundleException(path + ": not valid JSON"); }  // what JsonUtility throws
            if (value == null) throw new BundleException(path + ": not valid JSON");
            return value;
        }

        static byte[] ReadBytes(string directory, string name, int expected)
        {
            if (string.IsNullOrEmpty(name) || name.Contains("..")) throw new BundleException("bad file name in the bundle: " + name);
            string path = Path.Combine(directory, name);
            if (!File.Exists(path)) throw new BundleException(path + ": missing from the bundle");
            byte[] raw = File.ReadAllBytes(path);
            if (raw.Length != expected)
                throw new BundleException(path + ": " + raw.Length + " bytes where " + expected + " are expected (truncated?)");
            return raw;
        }

        static float ReadSingle(byte[] raw, int offset)
        {
            if (!BitConverter.IsLittleEndian)
            {
                var swapped = new[] { raw[offset + 3], raw[offset + 2], raw[offset + 1], raw[offset] };
                return BitConverter.ToSingle(swapped, 0);
            }
            return BitConverter.ToSingle(raw, offset);
        }
    }
}
