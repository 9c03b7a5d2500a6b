// A test double of the UnityEngine API the package's C# uses, with Unity's signatures, so that
// the package is compiled (mcs, C# 7.2) against a separate assembly as in Unity, and its
// non-drawing logic runs under mono (tests/export/test_unity_mono.py).
//
// What works here as in Unity: Color/Color32 (and their conversions, rounding as Unity's),
// Vector2/3/4, Mathf, textures as CPU storage (Texture2D, Texture2DArray and Texture3D keep
// their texels: SetPixelData/SetPixels/SetPixels32 in, GetPixels/GetPixels32/GetPixel/
// GetRawTextureData out, rows bottom first, Texture3D red fastest as Unity's SetPixels),
// Texture3D.GetPixelBilinear (trilinear, clamp, texel centres at (i + 0.5)/n as a GPU samples),
// Material property storage, GameObject.AddComponent (Awake and OnEnable called as Unity does
// on an active object), Light, JsonUtility.FromJson (public fields of [Serializable] types, unknown
// keys ignored, missing keys leave the constructed value, ArgumentException on malformed JSON).
// Drawing (Graphics, RenderTexture, Camera, Shader) is signatures only: nothing is drawn.
using System;
using System.Collections;
using System.Collections.Generic;
using System.Globalization;
using System.Reflection;
using System.Text;

namespace UnityEngine
{
    public enum TextureFormat { Alpha8 = 1, RGB24 = 3, RGBA32 = 4, ARGB32 = 5, RHalf = 15, RGBAHalf = 17, RFloat = 18, RGBAFloat = 20 }
    public enum FilterMode { Point = 0, Bilinear = 1, Trilinear = 2 }
    public enum TextureWrapMode { Repeat = 0, Clamp = 1 }
    public enum RenderTextureFormat { ARGB32 = 0 }
    public enum RenderTextureReadWrite { Default = 0, Linear = 1, sRGB = 2 }
    public enum MeshTopology { Triangles = 0 }

    public struct Color
    {
        public float r, g, b, a;
        public Color(float r, float g, float b, float a) { this.r = r; this.g = g; this.b = b; this.a = a; }
        public Color(float r, float g, float b) : this(r, g, b, 1f) { }
        public static Color black { get { return new Color(0f, 0f, 0f, 1f); } }
        public static Color white { get { return new Color(1f, 1f, 1f, 1f); } }
        public static Color grey { get { return new Color(0.5f, 0.5f, 0.5f, 1f); } }
        public static Color gray { get { return grey; } }
        public static Color clear { get { return new Color(0f, 0f, 0f, 0f); } }
        public static Color red { get { return new Color(1f, 0f, 0f, 1f); } }
        public static Color green { get { return new Color(0f, 1f, 0f, 1f); } }
        public static Color yellow { get { return new Color(1f, 0.921568632f, 0.0156862754f, 1f); } }
        /// <summary>The sRGB-encoded colour decoded to linear (alpha kept), as Unity's Color.linear.</summary>
        public Color linear { get { return new Color(Mathf.GammaToLinearSpace(r), Mathf.GammaToLinearSpace(g), Mathf.GammaToLinearSpace(b), a); } }
        public Color gamma { get { return new Color(Mathf.LinearToGammaSpace(r), Mathf.LinearToGammaSpace(g), Mathf.LinearToGammaSpace(b), a); } }
        public float this[int index]
        {
            get { switch (index) { case 0: return r; case 1: return g; case 2: return b; case 3: return a; default: throw new IndexOutOfRangeException("Invalid Color index(" + index + ")!"); } }
            set { switch (index) { case 0: r = value; break; case 1: g = value; break; case 2: b = value; break; case 3: a = value; break; default: throw new IndexOutOfRangeException("Invalid Color index(" + index + ")!"); } }
        }
        public static Color operator *(Color c, float s) { return new Color(c.r * s, c.g * s, c.b * s, c.a * s); }
        public static Color operator *(Color x, Color y) { return new Color(x.r * y.r, x.g * y.g, x.b * y.b, x.a * y.a); }
        public static Color operator +(Color x, Color y) { return new Color(x.r + y.r, x.g + y.g, x.b + y.b, x.a + y.a); }
        public static bool operator ==(Color x, Color y) { return x.r == y.r && x.g == y.g && x.b == y.b && x.a == y.a; }
        public static bool operator !=(Color x, Color y) { return !(x == y); }
        public override bool Equals(object other) { return other is Color && this == (Color)other; }
        public override int GetHashCode() { return r.GetHashCode() ^ (g.GetHashCode() << 2) ^ (b.GetHashCode() >> 2) ^ (a.GetHashCode() >> 1); }
        public override string ToString() { return string.Format(CultureInfo.InvariantCulture, "RGBA({0:F3}, {1:F3}, {2:F3}, {3:F3})", r, g, b, a); }
    }

    public struct Color32
    {
        public byte r, g, b, a;
        public Color32(byte r, byte g, byte b, byte a) { this.r = r; this.g = g; this.b = b; this.a = a; }
        public static implicit operator Color(Color32 c) { return new Color(c.r / 255f, c.g / 255f, c.b / 255f, c.a / 255f); }
        // Unity: (byte)Mathf.Round(Mathf.Clamp01(c) * 255f); Mathf.Round rounds half to even
        public static implicit operator Color32(Color c)
        {
            return new Color32((byte)Mathf.Round(Mathf.Clamp01(c.r) * 255f), (byte)Mathf.Round(Mathf.Clamp01(c.g) * 255f),
                               (byte)Mathf.Round(Mathf.Clamp01(c.b) * 255f), (byte)Mathf.Round(Mathf.Clamp01(c.a) * 255f));
        }
        public override string ToString() { return "RGBA(" + r + ", " + g + ", " + b + ", " + a + ")"; }
    }

    public struct Vector2
    {
        public float x, y;
        public Vector2(float x, float y) { this.x = x; this.y = y; }
    }

    public struct Vector3
    {
        public float x, y, z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 zero { get { return new Vector3(0f, 0f, 0f); } }
        public static Vector3 one { get { return new Vector3(1f, 1f, 1f); } }
        public static Vector3 up { get { return new Vector3(0f, 1f, 0f); } }
        public static Vector3 down { get { return new Vector3(0f, -1f, 0f); } }
        public static Vector3 forward { get { return new Vector3(0f, 0f, 1f); } }
        public static Vector3 back { get { return new Vector3(0f, 0f, -1f); } }
        public static Vector3 right { get { return new Vector3(1f, 0f, 0f); } }
        public static Vector3 left { get { return new Vector3(-1f, 0f, 0f); } }
        public float magnitude { get { return (float)Math.Sqrt(x * x + y * y + z * z); } }
        public Vector3 normalized { get { float m = magnitude; return m > 1e-5f ? new Vector3(x / m, y / m, z / m) : zero; } }
        public static Vector3 operator +(Vector3 p, Vector3 q) { return new Vector3(p.x + q.x, p.y + q.y, p.z + q.z); }
        public static Vector3 operator -(Vector3 p, Vector3 q) { return new Vector3(p.x - q.x, p.y - q.y, p.z - q.z); }
        public static Vector3 operator -(Vector3 p) { return new Vector3(-p.x, -p.y, -p.z); }
        public static Vector3 operator *(Vector3 p, float s) { return new Vector3(p.x * s, p.y * s, p.z * s); }
        public static Vector3 operator *(float s, Vector3 p) { return p * s; }
        public static Vector3 operator /(Vector3 p, float s) { return new Vector3(p.x / s, p.y / s, p.z / s); }
        public static float Dot(Vector3 p, Vector3 q) { return p.x * q.x + p.y * q.y + p.z * q.z; }
        public static float Distance(Vector3 p, Vector3 q) { return (p - q).magnitude; }
    }

    public struct Vector4
    {
        public float x, y, z, w;
        public Vector4(float x, float y, float z, float w) { this.x = x; this.y = y; this.z = z; this.w = w; }
        public float this[int index]
        {
            get { switch (index) { case 0: return x; case 1: return y; case 2: return z; case 3: return w; default: throw new IndexOutOfRangeException(); } }
            set { switch (index) { case 0: x = value; break; case 1: y = value; break; case 2: z = value; break; case 3: w = value; break; default: throw new IndexOutOfRangeException(); } }
        }
    }

    public struct Quaternion
    {
        public float x, y, z, w;
        public Quaternion(float x, float y, float z, float w) { this.x = x; this.y = y; this.z = z; this.w = w; }
        public static Quaternion identity { get { return new Quaternion(0f, 0f, 0f, 1f); } }
        public static Quaternion Euler(float x, float y, float z) { throw new NotSupportedException("test double: rotations are not computed"); }
        public static Quaternion LookRotation(Vector3 forward) { throw new NotSupportedException("test double: rotations are not computed"); }
    }

    public static class Mathf
    {
        public const float PI = 3.14159274f;
        public const float Epsilon = 1.401298E-45f;
        public static float Round(float f) { return (float)Math.Round(f); }   // half to even, as Unity
        public static int RoundToInt(float f) { return (int)Math.Round(f); }
        public static int FloorToInt(float f) { return (int)Math.Floor(f); }
        public static float Floor(float f) { return (float)Math.Floor(f); }
        public static float Clamp01(float value) { return value < 0f ? 0f : (value > 1f ? 1f : value); }
        public static float Clamp(float value, float min, float max) { return value < min ? min : (value > max ? max : value); }
        public static int Clamp(int value, int min, int max) { return value < min ? min : (value > max ? max : value); }
        public static float Min(float a, float b) { return a < b ? a : b; }
        public static float Max(float a, float b) { return a > b ? a : b; }
        public static int Min(int a, int b) { return a < b ? a : b; }
        public static int Max(int a, int b) { return a > b ? a : b; }
        public static float Abs(float f) { return Math.Abs(f); }
        public static float Sqrt(float f) { return (float)Math.Sqrt(f); }
        public static float Pow(float f, float p) { return (float)Math.Pow(f, p); }
        public static float Log(float f, float p) { return (float)Math.Log(f, p); }
        public static float Lerp(float a, float b, float t) { return a + (b - a) * Clamp01(t); }
        // Unity's GammaToLinearSpace / LinearToGammaSpace: the sRGB transfer function
        public static float GammaToLinearSpace(float value)
        {
            if (value <= 0.04045f) return value / 12.92f;
            if (value < 1f) return (float)Math.Pow((value + 0.055) / 1.055, 2.4);
            return (float)Math.Pow(value, 2.2);
        }
        public static float LinearToGammaSpace(float value)
        {
            if (value <= 0f) return 0f;
            if (value <= 0.0031308f) return 12.92f * value;
            if (value < 1f) return (float)(1.055 * Math.Pow(value, 0.4166667) - 0.055);
            return (float)Math.Pow(value, 0.45454545);
        }
    }

    public static class Debug
    {
        public static readonly List<string> Messages = new List<string>();   // test double: what was logged
        public static void Log(object message) { Messages.Add("log: " + message); }
        public static void LogWarning(object message) { Messages.Add("warning: " + message); }
        public static void LogError(object message) { Messages.Add("error: " + message); }
        public static void LogException(Exception exception) { Messages.Add("exception: " + exception.Message); }
    }

    public static class Application
    {
        public static string streamingAssetsPath = "StreamingAssets";   // test double: settable
        public static string persistentDataPath = "PersistentData";
        public static bool isPlaying = true;
        public static bool runInBackground;                              // VrPatchServer
        public static string unityVersion = "2021.3.0f1 (test double)";
    }

    public static class Time
    {
        public static float deltaTime = 1f / 90f;   // test double: settable
        public static float time;
        public static float unscaledTime;
    }

    public class Object
    {
        public string name { get; set; }
        public static void Destroy(Object obj) { }
        public static void DontDestroyOnLoad(Object target) { }
        public static T FindObjectOfType<T>() where T : Object { return null; }
        public static T Instantiate<T>(T original) where T : Object { return original; }
        public static implicit operator bool(Object exists) { return !ReferenceEquals(exists, null); }
    }

    [AttributeUsage(AttributeTargets.Field)] public sealed class SerializeField : Attribute { }
    [AttributeUsage(AttributeTargets.Field)] public sealed class TooltipAttribute : Attribute { public TooltipAttribute(string tooltip) { } }
    [AttributeUsage(AttributeTargets.Field)] public sealed class HeaderAttribute : Attribute { public HeaderAttribute(string header) { } }
    [AttributeUsage(AttributeTargets.Field)] public sealed class RangeAttribute : Attribute { public RangeAttribute(float min, float max) { } }
    [AttributeUsage(AttributeTargets.Class, AllowMultiple = true)] public sealed class RequireComponent : Attribute { public RequireComponent(Type type) { } }
    [AttributeUsage(AttributeTargets.Class)] public sealed class DisallowMultipleComponent : Attribute { }
    [AttributeUsage(AttributeTargets.Class)] public sealed class AddComponentMenu : Attribute { public AddComponentMenu(string menuName) { } }

    public class Shader : Object
    {
        public static Shader Find(string name) { return new Shader { name = name }; }   // test double: every name exists
    }

    public class Texture : Object
    {
        public FilterMode filterMode { get; set; }
        public TextureWrapMode wrapMode { get; set; }
        public int anisoLevel { get; set; }
        public virtual int width { get; set; }
        public virtual int height { get; set; }

        // test double: bytes per texel of the formats used, and the texel decoders
        internal static int BytesPerTexel(TextureFormat format)
        {
            switch (format)
            {
                case TextureFormat.Alpha8: return 1;
                case TextureFormat.RGB24: return 3;
                case TextureFormat.RGBA32: case TextureFormat.ARGB32: case TextureFormat.RFloat: return 4;
                case TextureFormat.RHalf: return 2;
                case TextureFormat.RGBAHalf: return 8;
                case TextureFormat.RGBAFloat: return 16;
                default: throw new ArgumentException("test double: texture format " + format + " is not implemented");
            }
        }

        internal static float HalfToFloat(ushort half)
        {
            int sign = (half >> 15) & 1, exponent = (half >> 10) & 31, mantissa = half & 1023;
            double value;
            if (exponent == 0) value = mantissa * Math.Pow(2, -24);
            else if (exponent == 31) value = mantissa == 0 ? double.PositiveInfinity : double.NaN;
            else value = (1024 + mantissa) * Math.Pow(2, exponent - 25);
            return (float)(sign == 1 ? -value : value);
        }

        internal static Color Decode(TextureFormat format, byte[] raw, int offset)
        {
            switch (format)
            {
                case TextureFormat.Alpha8: return new Color(1f, 1f, 1f, raw[offset] / 255f);
                case TextureFormat.RGB24: return new Color32(raw[offset], raw[offset + 1], raw[offset + 2], 255);
                case TextureFormat.RGBA32: return new Color32(raw[offset], raw[offset + 1], raw[offset + 2], raw[offset + 3]);
                case TextureFormat.ARGB32: return new Color32(raw[offset + 1], raw[offset + 2], raw[offset + 3], raw[offset]);
                case TextureFormat.RFloat: return new Color(BitConverter.ToSingle(raw, offset), 0f, 0f, 1f);
                case TextureFormat.RHalf: return new Color(HalfToFloat(BitConverter.ToUInt16(raw, offset)), 0f, 0f, 1f);
                case TextureFormat.RGBAHalf:
                    return new Color(HalfToFloat(BitConverter.ToUInt16(raw, offset)), HalfToFloat(BitConverter.ToUInt16(raw, offset + 2)),
                                     HalfToFloat(BitConverter.ToUInt16(raw, offset + 4)), HalfToFloat(BitConverter.ToUInt16(raw, offset + 6)));
                case TextureFormat.RGBAFloat:
                    return new Color(BitConverter.ToSingle(raw, offset), BitConverter.ToSingle(raw, offset + 4),
                                     BitConverter.ToSingle(raw, offset + 8), BitConverter.ToSingle(raw, offset + 12));
                default: throw new ArgumentException("test double: texture format " + format + " is not implemented");
            }
        }

        internal static void Encode(TextureFormat format, Color colour, byte[] raw, int offset)
        {
            switch (format)
            {
                case TextureFormat.RGBA32:
                {
                    Color32 c = colour; raw[offset] = c.r; raw[offset + 1] = c.g; raw[offset + 2] = c.b; raw[offset + 3] = c.a; return;
                }
                case TextureFormat.RGB24:
                {
                    Color32 c = colour; raw[offset] = c.r; raw[offset + 1] = c.g; raw[offset + 2] = c.b; return;
                }
                case TextureFormat.RFloat: Buffer.BlockCopy(BitConverter.GetBytes(colour.r), 0, raw, offset, 4); return;
                case TextureFormat.RGBAFloat:
                    for (int i = 0; i < 4; ++i) Buffer.BlockCopy(BitConverter.GetBytes(colour[i]), 0, raw, offset + 4 * i, 4);
                    return;
                default: throw new ArgumentException("test double: writing texture format " + format + " is not implemented");
            }
        }

        internal static byte[] RawBytes<T>(T[] data, int start, int expected)
        {
            var bytes = new byte[Buffer.ByteLength(data)];   // primitive element types only, as Unity's blittable T
            Buffer.BlockCopy(data, 0, bytes, 0, bytes.Length);
            int skip = start * (bytes.Length / Math.Max(1, data.Length));
            if (bytes.Length - skip < expected)
                throw new ArgumentException("SetPixelData: " + (bytes.Length - skip) + " bytes given where " + expected + " are needed");
            var raw = new byte[expected];
            Buffer.BlockCopy(bytes, skip, raw, 0, expected);
            return raw;
        }
    }

    public class Texture2D : Texture
    {
        public TextureFormat format { get; private set; }
        public bool isReadable { get; private set; }
        public bool linearStorage { get; private set; }   // test double: the `linear` argument (false: sRGB sampled)
        byte[] texels;

        public Texture2D(int width, int height) : this(width, height, TextureFormat.RGBA32, true, false) { }
        public Texture2D(int width, int height, TextureFormat textureFormat, bool mipChain) : this(width, height, textureFormat, mipChain, false) { }
        public Texture2D(int width, int height, TextureFormat textureFormat, bool mipChain, bool linear)
        {
            if (width <= 0 || height <= 0) throw new ArgumentException("Texture2D: width and height must be positive");
            this.width = width; this.height = height; format = textureFormat; linearStorage = linear; isReadable = true;
            texels = new byte[width * height * BytesPerTexel(textureFormat)];
        }

        void CheckReadable() { if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable"); }
        public void SetPixelData<T>(T[] data, int mipLevel, int sourceDataStartIndex = 0)
        {
            CheckReadable();
            texels = RawBytes(data, sourceDataStartIndex, texels.Length);
        }
        public byte[] GetRawTextureData() { CheckReadable(); return (byte[])texels.Clone(); }
        public Color GetPixel(int x, int y)
        {
            CheckReadable();
            x = Math.Min(Math.Max(x, 0), width - 1); y = Math.Min(Math.Max(y, 0), height - 1);
            return Decode(format, texels, (y * width + x) * BytesPerTexel(format));
        }
        public Color[] GetPixels()
        {
            var colours = new Color[width * height];
            for (int i = 0; i < colours.Length; ++i) colours[i] = GetPixel(i % width, i / width);
            return colours;
        }
        public Color32[] GetPixels32()
        {
            var colours = new Color32[width * height];
            for (int i = 0; i < colours.Length; ++i) colours[i] = GetPixel(i % width, i / width);
            return colours;
        }
        public void SetPixel(int x, int y, Color colour) { CheckReadable(); Encode(format, colour, texels, (y * width + x) * BytesPerTexel(format)); }
        public void SetPixels(Color[] colours)
        {
            if (colours.Length != width * height) throw new ArgumentException("SetPixels: " + colours.Length + " colours for " + width + "x" + height);
            for (int i = 0; i < colours.Length; ++i) SetPixel(i % width, i / width, colours[i]);
        }
        public void SetPixels32(Color32[] colours)
        {
            if (colours.Length != width * height) throw new ArgumentException("SetPixels32: " + colours.Length + " colours for " + width + "x" + height);
            for (int i = 0; i < colours.Length; ++i) SetPixel(i % width, i / width, colours[i]);
        }
        public bool LoadImage(byte[] data) { throw new NotSupportedException("test double: image decoding is not implemented"); }
        public void Apply() { }
        public void Apply(bool updateMipmaps) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { if (makeNoLongerReadable) isReadable = false; }
    }

    public class Texture2DArray : Texture
    {
        public int depth { get; private set; }
        public TextureFormat format { get; private set; }
        public bool isReadable { get; private set; }
        readonly byte[][] elements;

        public Texture2DArray(int width, int height, int depth, TextureFormat textureFormat, bool mipChain, bool linear)
        {
            this.width = width; this.height = height; this.depth = depth; format = textureFormat; isReadable = true;
            elements = new byte[depth][];
            for (int i = 0; i < depth; ++i) elements[i] = new byte[width * height * BytesPerTexel(textureFormat)];
        }
        public void SetPixelData<T>(T[] data, int mipLevel, int element, int sourceDataStartIndex = 0)
        {
            if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable");
            elements[element] = RawBytes(data, sourceDataStartIndex, elements[element].Length);
        }
        public Color[] GetPixels(int arrayElement, int miplevel = 0)
        {
            if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable");
            return TestDoubleTexels(arrayElement);
        }
        /// <summary>Not Unity API: the texels as uploaded (what the GPU holds), readable or not.</summary>
        public Color[] TestDoubleTexels(int arrayElement)
        {
            var colours = new Color[width * height];
            for (int i = 0; i < colours.Length; ++i) colours[i] = Decode(format, elements[arrayElement], i * BytesPerTexel(format));
            return colours;
        }
        public void Apply(bool updateMipmaps) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { if (makeNoLongerReadable) isReadable = false; }
    }

    public class Texture3D : Texture
    {
        public int depth { get; private set; }
        public TextureFormat format { get; private set; }
        public bool isReadable { get; private set; }
        Color[] texels;

        public Texture3D(int width, int height, int depth, TextureFormat textureFormat, bool mipChain)
        {
            this.width = width; this.height = height; this.depth = depth; format = textureFormat; isReadable = true;
            texels = new Color[width * height * depth];
        }
        public void SetPixels(Color[] colors)
        {
            if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable");
            if (colors.Length != texels.Length) throw new ArgumentException("SetPixels: " + colors.Length + " colours for " + texels.Length + " texels");
            texels = (Color[])colors.Clone();   // RGBAFloat keeps float32 exactly
        }
        public Color[] GetPixels() { if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable"); return (Color[])texels.Clone(); }
        public Color GetPixel(int x, int y, int z)
        {
            x = Math.Min(Math.Max(x, 0), width - 1); y = Math.Min(Math.Max(y, 0), height - 1); z = Math.Min(Math.Max(z, 0), depth - 1);
            return texels[x + width * (y + height * z)];
        }
        // test double of GPU filtering: texel i's centre at (i + 0.5)/n, clamp to edge, trilinear
        // in float32 (real hardware may quantise the weights, to 8 bits on many GPUs)
        public Color GetPixelBilinear(float u, float v, float w, int mipLevel = 0)
        {
            if (!isReadable) throw new UnityException("Texture '" + name + "' is not readable");
            float px = u * width - 0.5f, py = v * height - 0.5f, pz = w * depth - 0.5f;
            int x0 = (int)Math.Floor(px), y0 = (int)Math.Floor(py), z0 = (int)Math.Floor(pz);
            float fx = px - x0, fy = py - y0, fz = pz - z0;
            var result = new Color(0f, 0f, 0f, 0f);
            for (int dz = 0; dz < 2; ++dz)
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx)
                    {
                        float weight = (dz == 1 ? fz : 1f - fz) * (dy == 1 ? fy : 1f - fy) * (dx == 1 ? fx : 1f - fx);
                        result = result + GetPixel(x0 + dx, y0 + dy, z0 + dz) * weight;
                    }
            return result;
        }
        public void Apply(bool updateMipmaps) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { if (makeNoLongerReadable) isReadable = false; }
    }

    public class RenderTexture : Texture
    {
        public RenderTexture(int width, int height, int depth, RenderTextureFormat format, RenderTextureReadWrite readWrite) { this.width = width; this.height = height; }
        public static RenderTexture active { get; set; }
        public bool Create() { return true; }
        public void Release() { }
    }

    public static class Graphics
    {
        public static void SetRenderTarget(RenderTexture rt) { }
        public static void DrawProceduralNow(MeshTopology topology, int vertexCount, int instanceCount = 1) { }
        public static void CopyTexture(Texture src, Texture dst) { }
    }

    public class UnityException : Exception
    {
        public UnityException(string message) : base(message) { }
    }

    public class Material : Object
    {
        readonly Dictionary<string, object> properties = new Dictionary<string, object>();   // test double: what was set
        public Shader shader { get; set; }
        public Material(Shader shader) { this.shader = shader; }
        public Material(Material source) { shader = source.shader; foreach (var pair in source.properties) properties[pair.Key] = pair.Value; }
        public Texture mainTexture { get { return GetTexture("_MainTex"); } set { SetTexture("_MainTex", value); } }
        public Color color { get { return GetColor("_Color"); } set { SetColor("_Color", value); } }
        public bool HasProperty(string name) { return properties.ContainsKey(name); }
        public bool SetPass(int pass) { return true; }
        public void SetTexture(string name, Texture value) { properties[name] = value; }
        public Texture GetTexture(string name) { object value; return properties.TryGetValue(name, out value) ? value as Texture : null; }
        public void SetVectorArray(string name, Vector4[] values) { properties[name] = (Vector4[])values.Clone(); }
        public Vector4[] GetVectorArray(string name) { return (Vector4[])properties[name]; }
        public void SetVector(string name, Vector4 value) { properties[name] = value; }
        public Vector4 GetVector(string name) { return (Vector4)properties[name]; }
        public void SetInt(string name, int value) { properties[name] = value; }
        public int GetInt(string name) { return (int)properties[name]; }
        public void SetFloat(string name, float value) { properties[name] = value; }
        public float GetFloat(string name) { return (float)properties[name]; }
        public void SetColor(string name, Color value) { properties[name] = value; }
        public Color GetColor(string name) { object value; return properties.TryGetValue(name, out value) ? (Color)value : new Color(0f, 0f, 0f, 0f); }
    }

    public class Component : Object
    {
        public GameObject gameObject { get; internal set; }
        public Transform transform { get { return gameObject.transform; } }
        public T GetComponent<T>() where T : Component { return gameObject.GetComponent<T>(); }
    }

    public class Transform : Component
    {
        public Vector3 position { get; set; }
        public Vector3 localPosition { get; set; }
        public Vector3 localScale { get; set; }
        public Quaternion rotation { get; set; }
        public Quaternion localRotation { get; set; }
        public Vector3 forward { get; set; }
        public Transform parent { get; private set; }
        public void SetParent(Transform parent, bool worldPositionStays) { this.parent = parent; }
        public void SetParent(Transform parent) { this.parent = parent; }
        public void LookAt(Vector3 worldPosition) { }
    }

    public class Behaviour : Component
    {
        public bool enabled { get; set; } = true;
    }

    public class MonoBehaviour : Behaviour
    {
        // VrPatchServer: coroutines are compiled, never run here
        public Coroutine StartCoroutine(System.Collections.IEnumerator routine) { return new Coroutine(); }
        public void StopAllCoroutines() { }
    }

    public sealed class Coroutine { }
    public sealed class WaitForEndOfFrame { }

    public enum LightType { Spot = 0, Directional = 1, Point = 2 }

    public sealed class Light : Behaviour
    {
        public LightType type { get; set; }
        public Color color { get; set; } = Color.white;
        public float intensity { get; set; } = 1f;
        public float range { get; set; } = 10f;
        public float spotAngle { get; set; } = 30f;
    }

    public class Renderer : Component
    {
        public Material sharedMaterial { get; set; }
        public Material material { get { return sharedMaterial; } set { sharedMaterial = value; } }   // test double: no per-renderer copy
    }

    public class MeshRenderer : Renderer { }

    public sealed class GameObject : Object
    {
        readonly List<Component> components = new List<Component>();
        public Transform transform { get; private set; }
        public bool activeSelf { get; private set; } = true;
        public GameObject() : this("New Game Object") { }
        public GameObject(string name)
        {
            this.name = name;
            transform = new Transform { gameObject = this, localScale = Vector3.one, rotation = Quaternion.identity, forward = Vector3.forward };
            components.Add(transform);
        }
        public T AddComponent<T>() where T : Component, new()
        {
            var component = new T { gameObject = this };
            components.Add(component);
            if (activeSelf)   // Unity calls Awake, then OnEnable, on an active object
                foreach (string message in new[] { "Awake", "OnEnable" })
                {
                    MethodInfo method = typeof(T).GetMethod(message, BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic, null, Type.EmptyTypes, null);
                    if (method != null)
                        try { method.Invoke(component, null); }
                        catch (TargetInvocationException error) { throw error.InnerException; }
                }
            return component;
        }
        public T GetComponent<T>() where T : Component
        {
            foreach (var component in components) if (component is T) return (T)component;
            return null;
        }
        public void SetActive(bool value) { activeSelf = value; }
        public int layer { get; set; }                                   // VrPatchServer
        public T[] GetComponents<T>() where T : Component { var found = new List<T>(); foreach (var c in components) if (c is T) found.Add((T)c); return found.ToArray(); }
        // test double: a primitive has a MeshRenderer and a Collider, as in Unity
        public static GameObject CreatePrimitive(PrimitiveType type)
        {
            var primitive = new GameObject(type.ToString());
            primitive.AddComponent<MeshRenderer>();
            primitive.AddComponent<Collider>();
            return primitive;
        }
    }

    /// <summary>Test double of Unity's JsonUtility (see the header of this file).</summary>
    public static class JsonUtility
    {
        public static T FromJson<T>(string json)
        {
            if (json == null) throw new ArgumentNullException("json");
            var parser = new JsonDoubleParser(json);
            object value = parser.ParseDocument();
            var fields = value as Dictionary<string, object>;
            if (fields == null) throw new ArgumentException("JSON must represent an object type.");
            return (T)Build(typeof(T), fields);
        }

        static object Build(Type type, Dictionary<string, object> fields)
        {
            object target = Activator.CreateInstance(type);
            foreach (FieldInfo field in type.GetFields(BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic))
            {
                if (!field.IsPublic && field.GetCustomAttribute(typeof(SerializeField)) == null) continue;
                if (field.IsInitOnly || field.IsNotSerialized) continue;
                object json;
                if (!fields.TryGetValue(field.Name, out json)) continue;   // missing: the constructed value stays
                if (!Serializable(field.FieldType)) continue;
                field.SetValue(target, Convert(field.FieldType, json, field.Name));
            }
            return target;
        }

        static bool Serializable(Type type)
        {
            if (type.IsArray) return type.GetArrayRank() == 1 && !type.GetElementType().IsArray && Serializable(type.GetElementType());
            if (type.IsPrimitive || type == typeof(string) || type.IsEnum) return true;
            if (type.IsGenericType && type.GetGenericTypeDefinition() == typeof(List<>)) return Serializable(type.GetGenericArguments()[0]);
            return type.GetCustomAttribute(typeof(SerializableAttribute)) != null && !type.IsAbstract;
        }

        static object Convert(Type type, object json, string name)
        {
            if (json == null) return type.IsValueType ? Activator.CreateInstance(type) : null;
            if (type == typeof(string))
            {
                if (json is string) return json;
                throw new ArgumentException("JSON parse error: '" + name + "' is not a string");
            }
            if (type == typeof(bool))
            {
                if (json is bool) return json;
                throw new ArgumentException("JSON parse error: '" + name + "' is not true or false");
            }
            if (type.IsPrimitive || type.IsEnum)
            {
                if (!(json is double)) throw new ArgumentException("JSON parse error: '" + name + "' is not a number");
                double number = (double)json;
                if (type == typeof(float)) return (float)number;
                if (type == typeof(double)) return number;
                if (Math.Floor(number) != number) throw new ArgumentException("test double: '" + name + "' = " + number + " is not an integer");
                return System.Convert.ChangeType(number, type.IsEnum ? Enum.GetUnderlyingType(type) : type, CultureInfo.InvariantCulture);
            }
            if (type.IsArray || (type.IsGenericType && type.GetGenericTypeDefinition() == typeof(List<>)))
            {
                var items = json as List<object>;
                if (items == null) throw new ArgumentException("JSON parse error: '" + name + "' is not an array");
                Type element = type.IsArray ? type.GetElementType() : type.GetGenericArguments()[0];
                if (type.IsArray)
                {
                    Array array = Array.CreateInstance(element, items.Count);
                    for (int i = 0; i < items.Count; ++i) array.SetValue(Convert(element, items[i], name), i);
                    return array;
                }
                var list = (IList)Activator.CreateInstance(type);
                foreach (var item in items) list.Add(Convert(element, item, name));
                return list;
            }
            var fields = json as Dictionary<string, object>;
            if (fields == null) throw new ArgumentException("JSON parse error: '" + name + "' is not an object");
            return Build(type, fields);
        }
    }

    // JSON text to Dictionary<string, object> / List<object> / double / string / bool / null
    sealed class JsonDoubleParser
    {
        readonly string text;
        int position;
        public JsonDoubleParser(string text) { this.text = text; }

        public object ParseDocument()
        {
            object value = ParseValue();
            SkipSpace();
            if (position != text.Length) Fail("text after the JSON value");
            return value;
        }

        void Fail(string what) { throw new ArgumentException("JSON parse error: " + what + " at character " + position); }

        void SkipSpace() { while (position < text.Length && char.IsWhiteSpace(text[position])) ++position; }

        object ParseValue()
        {
            SkipSpace();
            if (position >= text.Length) Fail("unexpected end");
            char c = text[position];
            if (c == '{') return ParseObject();
            if (c == '[') return ParseArray();
            if (c == '"') return ParseString();
            if (Literal("true")) return true;
            if (Literal("false")) return false;
            if (Literal("null")) return null;
            return ParseNumber();
        }

        bool Literal(string word)
        {
            if (string.CompareOrdinal(text, position, word, 0, word.Length) != 0) return false;
            position += word.Length;
            return true;
        }

        Dictionary<string, object> ParseObject()
        {
            var result = new Dictionary<string, object>();
            ++position;
            SkipSpace();
            if (position < text.Length && text[position] == '}') { ++position; return result; }
            while (true)
            {
                SkipSpace();
                if (position >= text.Length || text[position] != '"') Fail("a key expected");
                string key = ParseString();
                SkipSpace();
                if (position >= text.Length || text[position] != ':') Fail("':' expected");
                ++position;
                result[key] = ParseValue();
                SkipSpace();
                if (position < text.Length && text[position] == ',') { ++position; continue; }
                if (position < text.Length && text[position] == '}') { ++position; return result; }
                Fail("',' or '}' expected");
            }
        }

        List<object> ParseArray()
        {
            var result = new List<object>();
            ++position;
            SkipSpace();
            if (position < text.Length && text[position] == ']') { ++position; return result; }
            while (true)
            {
                result.Add(ParseValue());
                SkipSpace();
                if (position < text.Length && text[position] == ',') { ++position; continue; }
                if (position < text.Length && text[position] == ']') { ++position; return result; }
                Fail("',' or ']' expected");
            }
        }

        string ParseString()
        {
            var builder = new StringBuilder();
            ++position;
            while (true)
            {
                if (position >= text.Length) Fail("unterminated string");
                char c = text[position++];
                if (c == '"') return builder.ToString();
                if (c != '\\') { builder.Append(c); continue; }
                if (position >= text.Length) Fail("unterminated escape");
                char e = text[position++];
                switch (e)
                {
                    case '"': builder.Append('"'); break;
                    case '\\': builder.Append('\\'); break;
                    case '/': builder.Append('/'); break;
                    case 'b': builder.Append('\b'); break;
                    case 'f': builder.Append('\f'); break;
                    case 'n': builder.Append('\n'); break;
                    case 'r': builder.Append('\r'); break;
                    case 't': builder.Append('\t'); break;
                    case 'u':
                        if (position + 4 > text.Length) Fail("short \\u escape");
                        builder.Append((char)int.Parse(text.Substring(position, 4), NumberStyles.HexNumber, CultureInfo.InvariantCulture));
                        position += 4;
                        break;
                    default: Fail("bad escape"); break;
                }
            }
        }

        double ParseNumber()
        {
            int start = position;
            while (position < text.Length && "+-0123456789.eE".IndexOf(text[position]) >= 0) ++position;
            double value;
            if (position == start || !double.TryParse(text.Substring(start, position - start), NumberStyles.Float, CultureInfo.InvariantCulture, out value))
                Fail("not a JSON value");
            return double.Parse(text.Substring(start, position - start), NumberStyles.Float, CultureInfo.InvariantCulture);
        }
    }
}

// --- Signatures the Lightbooth sample uses (Samples~/Lightbooth): compiled, never run here ---
namespace UnityEngine
{
    public enum PrimitiveType { Sphere = 0, Capsule = 1, Cylinder = 2, Cube = 3, Plane = 4, Quad = 5 }
    public enum ColorSpace { Uninitialized = -1, Gamma = 0, Linear = 1 }
    public enum TextAnchor { UpperLeft = 0, UpperCenter = 1, UpperRight = 2, MiddleLeft = 3, MiddleCenter = 4, MiddleRight = 5, LowerLeft = 6, LowerCenter = 7, LowerRight = 8 }
    public enum KeyCode { None = 0, Space = 32, Alpha1 = 49, Alpha2 = 50, L = 108, N = 110 }

    public static class QualitySettings
    {
        public static ColorSpace activeColorSpace = ColorSpace.Linear;   // test double: settable
    }

    public static class Input
    {
        public static bool GetKeyDown(KeyCode key) { return false; }
    }

    public class Collider : Component { }

    public class Camera : Behaviour
    {
        public static Camera main { get; set; }
        // VrPatchServer's patch camera
        public static Camera[] allCameras { get { return new Camera[0]; } }
        public CameraClearFlags clearFlags { get; set; }
        public Color backgroundColor { get; set; }
        public int cullingMask { get; set; } = -1;
        public float depth { get; set; }
        public bool allowHDR { get; set; } = true;
        public bool allowMSAA { get; set; } = true;
        public bool allowDynamicResolution { get; set; }
        public bool useOcclusionCulling { get; set; } = true;
        public float nearClipPlane { get; set; } = 0.3f;
        public float farClipPlane { get; set; } = 1000f;
        public StereoTargetEyeMask stereoTargetEye { get; set; } = StereoTargetEyeMask.Both;
    }

    public enum CameraClearFlags { Skybox = 1, SolidColor = 2, Depth = 3, Nothing = 4 }
    [Flags] public enum StereoTargetEyeMask { None = 0, Left = 1, Right = 2, Both = 3 }

    public struct Bounds
    {
        public Vector3 center, size;
        public Bounds(Vector3 center, Vector3 size) { this.center = center; this.size = size; }
    }

    public sealed class Mesh : Object
    {
        public Vector3[] vertices { get; set; }
        public Vector2[] uv { get; set; }
        public int[] triangles { get; set; }
        public Bounds bounds { get; set; }
    }

    public sealed class MeshFilter : Component
    {
        public Mesh sharedMesh { get; set; }
    }

    public struct Ray
    {
        public Vector3 origin, direction;
        public Ray(Vector3 origin, Vector3 direction) { this.origin = origin; this.direction = direction; }
    }

    public struct RaycastHit
    {
        public Collider collider { get; set; }
        public Vector3 point { get; set; }
    }

    public static class Physics
    {
        public static bool Raycast(Ray ray, out RaycastHit hitInfo, float maxDistance) { hitInfo = new RaycastHit(); return false; }
    }

    public class Font : Object
    {
        public Material material { get; set; }
    }

    public sealed class TextMesh : Component
    {
        public string text { get; set; }
        public Font font { get; set; }
        public int fontSize { get; set; }
        public float characterSize { get; set; } = 1f;
        public TextAnchor anchor { get; set; }
        public Color color { get; set; } = Color.white;
    }

    public static class Resources
    {
        public static T GetBuiltinResource<T>(string path) where T : Object { return null; }
    }

}

namespace UnityEngine.XR
{
    [Flags]
    public enum InputDeviceCharacteristics : uint { None = 0, HeadMounted = 1, Camera = 2, HeldInHand = 4, HandTracking = 8, EyeTracking = 16, TrackedDevice = 32, Controller = 64, TrackingReference = 128, Left = 256, Right = 512, Simulated6DOF = 1024 }

    public struct InputFeatureUsage<T>
    {
        public string name { get; private set; }
        public InputFeatureUsage(string usageName) { name = usageName; }
    }

    public static class CommonUsages
    {
        public static InputFeatureUsage<bool> primaryButton = new InputFeatureUsage<bool>("PrimaryButton");
        public static InputFeatureUsage<bool> secondaryButton = new InputFeatureUsage<bool>("SecondaryButton");
        public static InputFeatureUsage<bool> triggerButton = new InputFeatureUsage<bool>("TriggerButton");
    }

    public struct InputDevice
    {
        public bool isValid { get { return false; } }
        public string name { get { return ""; } }
        public bool TryGetFeatureValue(InputFeatureUsage<bool> usage, out bool value) { value = false; return false; }
    }

    public static class XRSettings
    {
        public static string loadedDeviceName = "";                      // VrPatchServer; test double: settable
    }

    public static class InputDevices
    {
        public static void GetDevicesWithCharacteristics(InputDeviceCharacteristics desiredCharacteristics, System.Collections.Generic.List<InputDevice> inputDevices) { inputDevices.Clear(); }
    }
}
