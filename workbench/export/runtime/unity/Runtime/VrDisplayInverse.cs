// The display inverse for sRGB-authored content: a texture pre-pass. Put it on a GameObject whose
// Renderer shows sRGB-authored content unlit (a photo, a video still, a UI panel, a skybox
// texture, an unlit material): at enable it replaces the material's texture by a copy whose
// texels are display_inverse.cube applied to the authored ones (engine sRGB output -> HMD DAC),
// so the headset shows the colours the content was authored to have on an ideal sRGB display
// (sRGB white = D65 at k * Y_white).
//
// Why a texture pre-pass and not a post pass over the frame:
// - a post pass would also transform what level 1 and level 2 already put in DAC (the bundle's
//   contract: never apply the inverse to level-1/level-2 output); a pre-pass touches only the
//   textures it is given;
// - unlit, an sRGB texel reaches the frame buffer unchanged (Linear: decoded on sampling and
//   encoded on writing; Gamma: never converted), so converting the texel once is converting
//   the pixel, with no cost per frame and per eye at 90 Hz and nothing that depends on the render
//   pipeline or on single-pass stereo;
// - it is C# on the CPU (VrCubeLut.ApplyToPixels), the same arithmetic as the bundle's reference
//   consumer, so it is executed and checked where the GPU path cannot be.
// Limits: lit content is what levels 1 and 2 are for; a material colour tint other than white
// multiplies after the pre-pass; filtering between texels of different colours (bilinear,
// mipmaps) interpolates DAC values instead of sRGB ones (exact at texel centres and 1:1); the
// source texture must be readable (Read/Write enabled in its import settings). For a whole-frame
// grade on content that is all sRGB, VrColourBundle.LoadDisplayInverseCube gives the Texture3D
// (sample it at VrCubeLut.TextureCoordinate; HDRP/URP colour lookup takes the .cube directly).
using System.Collections.Generic;
using UnityEngine;

namespace VrColourWorkbench
{
    [AddComponentMenu("VR Colour Workbench/Display Inverse (sRGB content)")]
    public sealed class VrDisplayInverse : MonoBehaviour
    {
        [Tooltip("The bundle folder: relative to StreamingAssets, or absolute")]
        public string bundleFolder = "headset";
        [Tooltip("Renderer whose material shows sRGB-authored content; empty: this GameObject's")]
        public Renderer targetRenderer;
        [Tooltip("Texture property to convert: _MainTex (Built-in), _BaseMap (URP), _UnlitColorMap (HDRP Unlit)")]
        public string textureProperty = "_MainTex";

        /// <summary>The texture as authored, and its converted copy (null before the pre-pass).</summary>
        public Texture2D Authored { get; private set; }
        public Texture2D Converted { get; private set; }

        static readonly Dictionary<Texture2D, Texture2D> converted = new Dictionary<Texture2D, Texture2D>();

        void OnEnable()
        {
            try { Apply(); }
            catch (BundleException error) { Debug.LogError("VrDisplayInverse: " + error.Message); }
            catch (UnityException error) { Debug.LogError("VrDisplayInverse: " + error.Message + " (enable Read/Write in the texture's import settings)"); }
        }

        void OnDisable()
        {
            if (Authored != null) TargetMaterial().SetTexture(textureProperty, Authored);   // back as authored
        }

        /// <summary>Replaces the material's texture by its display-inverse copy (made once per source texture).</summary>
        public void Apply()
        {
            Material material = TargetMaterial();
            Texture2D source = material.GetTexture(textureProperty) as Texture2D;
            if (source == null) throw new BundleException("VrDisplayInverse: the material has no Texture2D in " + textureProperty);
            if (source == Converted) return;   // already applied
            Authored = source;
            Converted = Convert(VrColourBundle.Shared(bundleFolder).LoadDisplayInverseLut(), source);
            material.SetTexture(textureProperty, Converted);
        }

        /// <summary>The display-inverse copy of an sRGB-authored, readable texture (cached per texture).</summary>
        public static Texture2D Convert(VrCubeLut lut, Texture2D source)
        {
            Texture2D copy;
            if (converted.TryGetValue(source, out copy) && copy != null) return copy;
            copy = new Texture2D(source.width, source.height, TextureFormat.RGBA32, false, false);   // sRGB sampled
            copy.name = source.name + " (display inverse)";
            copy.filterMode = source.filterMode;
            copy.wrapMode = source.wrapMode;
            copy.SetPixels32(lut.ApplyToPixels(source.GetPixels32()));
            copy.Apply(false);
            converted[source] = copy;
            return copy;
        }

        Material TargetMaterial()
        {
            Renderer renderer = targetRenderer != null ? targetRenderer : GetComponent<Renderer>();
            if (renderer == null) throw new BundleException("VrDisplayInverse: no Renderer to convert the texture of");
            return renderer.material;
        }
    }
}
