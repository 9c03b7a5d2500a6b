// Level 2 in a scene: re-authors a material's albedo from one of the bundle's level-2 cubes
// whenever the light (a VrBundleLight) changes source. Put it on a GameObject with a Renderer.
//
// GPU path: VrColourBundle.Relight draws the level-2 pass (Shaders/VrLevel2Relight.shader) into
//   the albedo texture: about a millisecond for a 1024^2 cube on a desktop GPU, every frame if
//   needed. Needs "Hidden/VrColourWorkbench/Level2Relight" in the build (Always Included Shaders,
//   or a material referencing it: relightMaterial).
// CPU path: VrColourBundle.RelightCpu (VrLevel2Cpu) computes the same texels in C# and uploads
//   them: no shader, no RenderTexture, readable texels; tens of milliseconds per million texels,
//   so for a light change, not for every frame.
// The albedo is an sRGB Texture2D of the cube's size with point filtering (a level-2 texel is
// exactly its value); the material's light must be the level-2 light colour (light_rgb8 of the
// cube's lights.json, equal to lights.json rgb8: what VrBundleLight sets). Texels the light cannot
// carry have alpha 0 (UnreachableTexels counts them).
using UnityEngine;

namespace VrColourWorkbench
{
    [AddComponentMenu("VR Colour Workbench/Level 2 Material")]
    public sealed class VrLevel2Material : MonoBehaviour
    {
        public enum RelightPath { Gpu, Cpu }

        [Tooltip("The VrBundleLight whose source this material follows (its bundle is used)")]
        public VrBundleLight bundleLight;
        [Tooltip("Name of a level-2 cube of the bundle (bundle.json cubes)")]
        public string cube = "";
        [Tooltip("Renderer whose material gets the albedo; empty: this GameObject's")]
        public Renderer targetRenderer;
        [Tooltip("Albedo texture property: _MainTex (Built-in), _BaseMap (URP), _BaseColorMap (HDRP)")]
        public string albedoProperty = "_MainTex";
        public RelightPath path = RelightPath.Gpu;
        [Tooltip("GPU path: a material with Hidden/VrColourWorkbench/Level2Relight (found by name when empty)")]
        public Material relightMaterial;
        [Tooltip("Level 1 / level 2 switch: off shows fallbackAlbedo (the cube as authored) instead")]
        public bool level2 = true;
        [Tooltip("The albedo at level 1 (e.g. the cube's preview under D65, as authored)")]
        public Texture fallbackAlbedo;

        /// <summary>The re-authored albedo (null before the first relight).</summary>
        public Texture2D Albedo { get; private set; }
        /// <summary>The source the albedo was re-authored for.</summary>
        public string RelitFor { get; private set; }
        /// <summary>CPU path: texels of the last relight that the light cannot carry (alpha 0); -1 on the GPU path.</summary>
        public int UnreachableTexels { get; private set; }

        void OnEnable()
        {
            if (bundleLight == null) return;   // set it, then enable (the inspector does so before OnEnable)
            bundleLight.SourceChanged += OnSourceChanged;
            if (bundleLight.CurrentSource != null) OnSourceChanged(bundleLight.CurrentSource);
        }

        void OnDisable()
        {
            if (bundleLight != null) bundleLight.SourceChanged -= OnSourceChanged;
        }

        /// <summary>Follows a VrBundleLight from now on (what OnEnable does with the inspector's field).</summary>
        public void Follow(VrBundleLight light)
        {
            OnDisable();
            bundleLight = light;
            OnEnable();
        }

        void OnSourceChanged(string source)
        {
            try { Relight(source); }
            catch (BundleException error) { Debug.LogError("VrLevel2Material: " + error.Message); }
        }

        /// <summary>Re-authors the albedo for a source and puts it (or the level-1 fallback) in the material.</summary>
        public void Relight(string source)
        {
            VrColourBundle bundle = bundleLight.Bundle;
            if (bundle == null) throw new BundleException("VrLevel2Material: the VrBundleLight has no bundle loaded yet");
            Material material = TargetMaterial();
            if (!level2)
            {
                if (fallbackAlbedo != null) material.SetTexture(albedoProperty, fallbackAlbedo);
                RelitFor = null;
                return;
            }
            if (path == RelightPath.Cpu)
            {
                int unreachable;
                Albedo = bundle.RelightCpu(cube, source, Albedo, out unreachable);
                UnreachableTexels = unreachable;
            }
            else
            {
                if (relightMaterial == null) relightMaterial = new Material(Shader.Find("Hidden/VrColourWorkbench/Level2Relight"));
                Albedo = bundle.Relight(relightMaterial, cube, source, Albedo);
                UnreachableTexels = -1;
            }
            material.SetTexture(albedoProperty, Albedo);
            RelitFor = source;
        }

        /// <summary>The level 1 / level 2 switch: re-applies the current source at the chosen level.</summary>
        public void SetLevel2(bool on)
        {
            level2 = on;
            if (bundleLight != null && bundleLight.CurrentSource != null) Relight(bundleLight.CurrentSource);
        }

        Material TargetMaterial()
        {
            Renderer renderer = targetRenderer != null ? targetRenderer : GetComponent<Renderer>();
            if (renderer == null) throw new BundleException("VrLevel2Material: no Renderer to put the albedo on");
            return renderer.material;
        }
    }
}
