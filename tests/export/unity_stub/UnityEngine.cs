// A minimal stub of the UnityEngine types VrColourBundle.cs uses, with Unity's signatures,
// so that the loader is compiled (mcs, C# 7.2) against a separate assembly as in Unity.
// Nothing here runs: the bodies only satisfy the compiler.
using System;

namespace UnityEngine
{
    public enum TextureFormat { RGBA32 = 4, RGBAHalf = 17, RGBAFloat = 20, RFloat = 18 }
    public enum FilterMode { Point = 0, Bilinear = 1, Trilinear = 2 }
    public enum TextureWrapMode { Repeat = 0, Clamp = 1 }
    public enum RenderTextureFormat { ARGB32 = 0 }
    public enum RenderTextureReadWrite { Default = 0, Linear = 1, sRGB = 2 }
    public enum MeshTopology { Triangles = 0 }

    public struct Color
    {
        public float r, g, b, a;
        public Color(float r, float g, float b, float a) { this.r = r; this.g = g; this.b = b; this.a = a; }
    }

    public struct Color32
    {
        public byte r, g, b, a;
        public Color32(byte r, byte g, byte b, byte a) { this.r = r; this.g = g; this.b = b; this.a = a; }
        public static implicit operator Color(Color32 c) { return new Color(c.r / 255f, c.g / 255f, c.b / 255f, c.a / 255f); }
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

    public class Object { }

    public class Texture : Object
    {
        public FilterMode filterMode { get; set; }
        public TextureWrapMode wrapMode { get; set; }
    }

    public class Texture2D : Texture
    {
        public Texture2D(int width, int height, TextureFormat textureFormat, bool mipChain, bool linear) { }
        public void SetPixelData<T>(T[] data, int mipLevel, int sourceDataStartIndex = 0) { }
        public void Apply(bool updateMipmaps) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { }
    }

    public class Texture2DArray : Texture
    {
        public Texture2DArray(int width, int height, int depth, TextureFormat textureFormat, bool mipChain, bool linear) { }
        public void SetPixelData<T>(T[] data, int mipLevel, int element, int sourceDataStartIndex = 0) { }
        public void Apply(bool updateMipmaps) { }
        public void Apply(bool updateMipmaps, bool makeNoLongerReadable) { }
    }

    public class Texture3D : Texture
    {
        public Texture3D(int width, int height, int depth, TextureFormat textureFormat, bool mipChain) { }
        public void SetPixels(Color[] colors) { }
        public void Apply(bool updateMipmaps) { }
    }

    public class RenderTexture : Texture
    {
        public RenderTexture(int width, int height, int depth, RenderTextureFormat format, RenderTextureReadWrite readWrite) { }
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

    public class Material : Object
    {
        public bool SetPass(int pass) { return true; }
        public void SetTexture(string name, Texture value) { }
        public void SetVectorArray(string name, Vector4[] values) { }
        public void SetVector(string name, Vector4 value) { }
        public void SetInt(string name, int value) { }
        public void SetFloat(string name, float value) { }
    }

    public static class JsonUtility
    {
        public static T FromJson<T>(string json) { throw new NotImplementedException("stub"); }
    }
}
