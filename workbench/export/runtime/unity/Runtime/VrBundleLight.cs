// Level 1 in a scene: sets a Light's colour (and intensity) from the bundle's lights.json for a
// chosen source. Put it on the GameObject of the scene's one light.
//
// Colour: lights.json rgb8, the engine light colour (sRGB-encoded 8-bit, as Light.color takes it);
// its white diffuser reaches the headset at Y = k * Y_white (the XYZ of the record).
// Intensity, by IntensityUnit:
//   EngineUnit (Built-in, URP; the default): intensity 1. The bundle's engine model is
//     framebuffer_lin = albedo_lin * light_lin with light_lin the decoded rgb8: the colour already
//     carries k * Y_white, and 1 keeps Unity's light arithmetic (GammaToLinear(colour * intensity)
//     without lightsUseLinearIntensity, GammaToLinear(colour) * intensity with it) equal to it.
//   Physical (HDRP with physical light units): intensity = pi * k * Y_white lux for a directional
//     light (a Lambertian white diffuser facing it has luminance E / pi = k * Y_white cd/m2), and
//     FixedExposureEV100 = log2(k * Y_white / 1.2): the fixed exposure that maps that luminance
//     to 1.0 (HDRP: exposure = 1 / (1.2 * 2^EV100)); set it on the scene's Exposure override.
// SourceChanged fires after each change (VrLevel2Material listens to it).
using System;
using UnityEngine;

namespace VrColourWorkbench
{
    [AddComponentMenu("VR Colour Workbench/Bundle Light (level 1)")]
    [RequireComponent(typeof(Light))]
    public sealed class VrBundleLight : MonoBehaviour
    {
        public enum IntensityUnit { EngineUnit, Physical }

        [Tooltip("The bundle folder: relative to StreamingAssets, or absolute")]
        public string bundleFolder = "headset";
        [Tooltip("Source id of lights.json (e.g. cie-d65); empty: the bundle's first light")]
        public string sourceId = "";
        public IntensityUnit intensityUnit = IntensityUnit.EngineUnit;

        /// <summary>After each change of source: the new source id.</summary>
        public event Action<string> SourceChanged;

        public VrColourBundle Bundle { get; private set; }
        /// <summary>The source the light shows now (null before the first Apply).</summary>
        public string CurrentSource { get; private set; }
        /// <summary>k * Y_white of the current source's white diffuser (lights.json XYZ[1], the profile's scale).</summary>
        public float WhiteLuminance { get; private set; }
        /// <summary>Physical mode: the fixed exposure (EV100) mapping WhiteLuminance to 1.0.</summary>
        public float FixedExposureEV100 { get { return (float)(Math.Log(WhiteLuminance / 1.2) / Math.Log(2.0)); } }

        void OnEnable()
        {
            try { Select(string.IsNullOrEmpty(sourceId) ? null : sourceId); }
            catch (BundleException error) { Debug.LogError("VrBundleLight: " + error.Message); }
        }

        /// <summary>The bundle's source ids, for a selector.</summary>
        public string[] Sources() { return Load().LightIds(); }

        /// <summary>Shows a source (null: the bundle's first): sets the Light, then fires SourceChanged.</summary>
        public void Select(string id)
        {
            VrColourBundle bundle = Load();
            if (id == null)
            {
                string[] ids = bundle.LightIds();
                if (ids.Length == 0) throw new BundleException(bundleFolder + ": lights.json holds no light");
                id = ids[0];
            }
            LightEntry entry = bundle.FindLight(id);
            var target = GetComponent<Light>();
            if (target == null) throw new BundleException("VrBundleLight needs a Light on the same GameObject");
            target.color = bundle.LightColour(id);
            WhiteLuminance = entry.XYZ[1];
            target.intensity = intensityUnit == IntensityUnit.Physical ? Mathf.PI * WhiteLuminance : 1f;
            sourceId = id;
            CurrentSource = id;
            var handlers = SourceChanged;
            if (handlers != null) handlers(id);
        }

        /// <summary>The next source of the bundle after the current one (wrapping), shown.</summary>
        public void SelectNext(int step = 1)
        {
            string[] ids = Sources();
            int index = Array.IndexOf(ids, CurrentSource);
            Select(ids[((index < 0 ? 0 : index + step) % ids.Length + ids.Length) % ids.Length]);
        }

        VrColourBundle Load()
        {
            if (Bundle == null) Bundle = VrColourBundle.Shared(bundleFolder);
            return Bundle;
        }
    }
}
