// The virtual lightbooth, built in code at run time from a VR colour workbench bundle: a grey
// booth open at the front, a lamp (VrBundleLight), the ColorChecker board and an Ishihara plate
// (the bundle's level-2 cubes "colorchecker" and "ishihara", each a VrLevel2Material), a label,
// and two gaze buttons. Add this component to an empty GameObject of an empty scene (with your
// XR rig or just a Main Camera) and press Play, or build for the headset.
//
// Controls (headset or desktop):
//   next source    XR controller primary button (A / X), gaze at "SOURCE" for 1.5 s, or N / Space
//   level 1 / 2    XR controller secondary button (B / Y), gaze at "LEVEL" for 1.5 s, or L
// The keyboard needs the old Input Manager (Project Settings > Player > Active Input Handling:
// "Input Manager (Old)" or "Both"); with the Input System package alone it is switched off.
//
// Shading: VrColourWorkbench/BoothSurface (Resources/), unlit apart from the bundle's light:
// frame buffer (linear) = albedo (linear) x the light colour (lights.json "linear"), the engine
// model the bundle's numbers assume, in a Linear or a Gamma project; no ambient, no specular,
// no tonemapping. Level 1: the albedo is the cube as authored (level2/<cube>/preview.png, its
// sRGB under D65) under the source's level-1 light colour. Level 2: the albedo is re-authored
// for the source (VrLevel2Material, CPU path by default) under the same light colour. The walls
// are a flat grey as authored (no wall cube in the bundle): level 1 only.
//
// Built-in render pipeline and URP (the shader is a plain unlit pass); not HDRP.
using System;
using System.Collections.Generic;
using System.IO;
using UnityEngine;
using UnityEngine.XR;
using VrColourWorkbench;

namespace VrColourWorkbench.Samples
{
    public sealed class LightboothBootstrap : MonoBehaviour
    {
        [Tooltip("The bundle folder: relative to StreamingAssets, or absolute")]
        public string bundleFolder = "headset";
        public string colorCheckerCube = "colorchecker";
        public string ishiharaCube = "ishihara";
        [Tooltip("Level 2 on the GPU (needs Hidden/VrColourWorkbench/Level2Relight in Always Included Shaders) or in C# on the CPU")]
        public VrLevel2Material.RelightPath relightPath = VrLevel2Material.RelightPath.Cpu;
        [Tooltip("Where the booth's front-centre floor point goes, relative to the camera's start position (metres)")]
        public Vector3 boothOffset = new Vector3(0f, -0.35f, 0.9f);
        [Tooltip("Seconds of gaze on a button that press it")]
        public float gazeSeconds = 1.5f;

        // booth size in metres (the workbench's scene: 80 x 50 x 50 cm), board and plate widths
        const float Width = 0.8f, Height = 0.5f, Depth = 0.5f, BoardWidth = 0.34f, PlateWidth = 0.22f;
        const float WallGrey = 0.45f;   // the walls' flat reflectance, as the workbench's booth

        VrBundleLight lamp;
        readonly List<VrLevel2Material> surfaces = new List<VrLevel2Material>();
        readonly List<Material> boothMaterials = new List<Material>();
        TextMesh label;
        Collider sourceButton, levelButton;
        Collider gazed;
        float gazeTime;
        bool level2 = true, keyboard = true, primaryWas, secondaryWas;
        readonly List<InputDevice> controllers = new List<InputDevice>();

        void Start()
        {
            try { Build(); }
            catch (BundleException error) { Debug.LogError("Lightbooth: " + error.Message); enabled = false; }
        }

        void Build()
        {
            VrColourBundle bundle = VrColourBundle.Shared(bundleFolder);
            foreach (string cube in new[] { colorCheckerCube, ishiharaCube })
                if (Array.IndexOf(bundle.CubeNames(), cube) < 0)
                    throw new BundleException(bundleFolder + ": no level-2 cube '" + cube + "' (export with --cube " + cube + ".npz; see the sample's README)");
            Debug.Log("Lightbooth: colour space " + QualitySettings.activeColorSpace + ", bundle " + bundle.Directory);

            Camera eye = Camera.main;
            Vector3 origin = (eye != null ? eye.transform.position : Vector3.zero) + boothOffset;
            var root = new GameObject("Lightbooth");
            root.transform.position = origin;

            Shader surface = Shader.Find("VrColourWorkbench/BoothSurface");
            if (surface == null) throw new BundleException("shader VrColourWorkbench/BoothSurface not found (keep the sample's Resources folder)");
            byte grey = VrCubeLut.ToByte(Mathf.LinearToGammaSpace(WallGrey));   // authored sRGB of the grey walls
            Texture2D wall = Solid(new Color32(grey, grey, grey, 255));
            Quad(root, "floor", surface, wall, new Vector3(0f, 0f, Depth / 2), new Vector3(90f, 0f, 0f), new Vector3(Width, Depth, 1f));
            Quad(root, "ceiling", surface, wall, new Vector3(0f, Height, Depth / 2), new Vector3(-90f, 0f, 0f), new Vector3(Width, Depth, 1f));
            Quad(root, "back", surface, wall, new Vector3(0f, Height / 2, Depth), Vector3.zero, new Vector3(Width, Height, 1f));
            Quad(root, "left", surface, wall, new Vector3(-Width / 2, Height / 2, Depth / 2), new Vector3(0f, -90f, 0f), new Vector3(Depth, Height, 1f));
            Quad(root, "right", surface, wall, new Vector3(Width / 2, Height / 2, Depth / 2), new Vector3(0f, 90f, 0f), new Vector3(Depth, Height, 1f));

            var lampObject = new GameObject("Lamp (VrBundleLight)");
            lampObject.transform.SetParent(root.transform, false);
            lampObject.transform.localPosition = new Vector3(0f, Height - 0.02f, Depth / 2);
            lampObject.transform.localRotation = Quaternion.Euler(90f, 0f, 0f);
            Light light = lampObject.AddComponent<Light>();
            light.type = LightType.Directional;
            lampObject.SetActive(false);                       // fields first, then OnEnable
            lamp = lampObject.AddComponent<VrBundleLight>();
            lamp.bundleFolder = bundleFolder;

            surfaces.Add(Card(root, bundle, colorCheckerCube, surface, BoardWidth, new Vector3(-0.14f, 0.02f, Depth - 0.002f)));
            surfaces.Add(Card(root, bundle, ishiharaCube, surface, PlateWidth, new Vector3(0.22f, 0.06f, Depth - 0.002f)));

            var labelObject = new GameObject("Label");
            labelObject.transform.SetParent(root.transform, false);
            labelObject.transform.localPosition = new Vector3(0f, Height + 0.08f, Depth / 2);
            label = Text(labelObject);
            label.anchor = TextAnchor.MiddleCenter;
            label.characterSize = 0.01f;
            label.fontSize = 48;
            sourceButton = Button(root, "SOURCE", new Vector3(-0.2f, -0.08f, 0f));
            levelButton = Button(root, "LEVEL", new Vector3(0.2f, -0.08f, 0f));

            lamp.SourceChanged += OnSourceChanged;            // after the cards: they relight first
            lampObject.SetActive(true);                        // VrBundleLight.OnEnable: the first source
            if (lamp.CurrentSource == null) lamp.Select(null);
        }

        VrLevel2Material Card(GameObject root, VrColourBundle bundle, string cube, Shader surface, float width, Vector3 bottomCentre)
        {
            BundleCube entry = null;
            foreach (var candidate in bundle.Manifest.cubes) if (candidate.name == cube) entry = candidate;
            float height = width * entry.height / entry.width;
            Texture2D authored = new Texture2D(2, 2, TextureFormat.RGBA32, false, false);
            string preview = Path.Combine(bundle.Directory, entry.folder, "preview.png");
            if (!File.Exists(preview) || !authored.LoadImage(File.ReadAllBytes(preview)))
                throw new BundleException(preview + ": missing or not a PNG");
            authored.filterMode = FilterMode.Point;
            Renderer renderer = Quad(root, cube, surface, authored, bottomCentre + new Vector3(0f, height / 2, 0f), Vector3.zero,
                                     new Vector3(width, height, 1f));
            VrLevel2Material level2Material = renderer.gameObject.AddComponent<VrLevel2Material>();
            level2Material.cube = cube;
            level2Material.path = relightPath;
            level2Material.fallbackAlbedo = authored;
            level2Material.level2 = level2;
            level2Material.Follow(lamp);
            return level2Material;
        }

        Renderer Quad(GameObject root, string name, Shader shader, Texture texture, Vector3 position, Vector3 euler, Vector3 scale)
        {
            GameObject quad = GameObject.CreatePrimitive(PrimitiveType.Quad);
            quad.name = name;
            Destroy(quad.GetComponent<Collider>());
            quad.transform.SetParent(root.transform, false);
            quad.transform.localPosition = position;
            quad.transform.localRotation = Quaternion.Euler(euler.x, euler.y, euler.z);
            quad.transform.localScale = scale;
            var material = new Material(shader);
            material.mainTexture = texture;
            Renderer renderer = quad.GetComponent<Renderer>();
            renderer.material = material;
            boothMaterials.Add(renderer.material);
            return renderer;
        }

        Collider Button(GameObject root, string text, Vector3 position)
        {
            GameObject button = GameObject.CreatePrimitive(PrimitiveType.Cube);
            button.name = text;
            button.transform.SetParent(root.transform, false);
            button.transform.localPosition = position;
            button.transform.localScale = new Vector3(0.16f, 0.06f, 0.02f);
            var caption = new GameObject(text + " caption");
            caption.transform.SetParent(root.transform, false);
            caption.transform.localPosition = position + new Vector3(0f, 0f, -0.02f);
            TextMesh mesh = Text(caption);
            mesh.text = text;
            mesh.anchor = TextAnchor.MiddleCenter;
            mesh.characterSize = 0.008f;
            mesh.fontSize = 48;
            mesh.color = Color.black;
            return button.GetComponent<Collider>();
        }

        static TextMesh Text(GameObject holder)
        {
            TextMesh mesh = holder.AddComponent<TextMesh>();   // adds its MeshRenderer
            Font font = null;
            foreach (string name in new[] { "LegacyRuntime.ttf", "Arial.ttf" })   // 2022.2+, then older
            {
                try { font = Resources.GetBuiltinResource<Font>(name); }
                catch (ArgumentException) { font = null; }
                if (font != null) break;
            }
            if (font != null)
            {
                mesh.font = font;
                holder.GetComponent<Renderer>().material = font.material;
            }
            return mesh;
        }

        static Texture2D Solid(Color32 colour)
        {
            var texture = new Texture2D(1, 1, TextureFormat.RGBA32, false, false);
            texture.SetPixels32(new[] { colour });
            texture.Apply(false);
            return texture;
        }

        void OnSourceChanged(string source)
        {
            LightEntry entry = lamp.Bundle.FindLight(source);
            var linear = new Vector4(entry.linear[0], entry.linear[1], entry.linear[2], 1f);
            foreach (Material material in boothMaterials) material.SetVector("_VrLightLinear", linear);
            UpdateLabel();
        }

        void UpdateLabel()
        {
            LightEntry entry = lamp.Bundle.FindLight(lamp.CurrentSource);
            int unreachable = 0;
            foreach (var surface in surfaces) unreachable += Math.Max(0, surface.UnreachableTexels);
            label.text = entry.name + "  (" + entry.id + ")   level " + (level2 ? "2" : "1")
                         + (level2 && unreachable > 0 ? "   " + unreachable + " texels out of reach" : "");
        }

        void NextSource() { lamp.SelectNext(); }

        void ToggleLevel()
        {
            level2 = !level2;
            foreach (var surface in surfaces) surface.SetLevel2(level2);
            UpdateLabel();
        }

        void Update()
        {
            if (lamp == null || lamp.CurrentSource == null) return;
            Controllers();
            Keyboard();
            Gaze();
        }

        void Controllers()
        {
            controllers.Clear();
            InputDevices.GetDevicesWithCharacteristics(InputDeviceCharacteristics.Controller, controllers);
            bool primary = false, secondary = false;
            foreach (var device in controllers)
            {
                bool pressed;
                if (device.TryGetFeatureValue(CommonUsages.primaryButton, out pressed) && pressed) primary = true;
                if (device.TryGetFeatureValue(CommonUsages.secondaryButton, out pressed) && pressed) secondary = true;
            }
            if (primary && !primaryWas) NextSource();
            if (secondary && !secondaryWas) ToggleLevel();
            primaryWas = primary;
            secondaryWas = secondary;
        }

        void Keyboard()
        {
            if (!keyboard) return;
            try
            {
                if (Input.GetKeyDown(KeyCode.N) || Input.GetKeyDown(KeyCode.Space)) NextSource();
                if (Input.GetKeyDown(KeyCode.L)) ToggleLevel();
            }
            catch (InvalidOperationException)   // the project uses the Input System package only
            {
                keyboard = false;
                Debug.Log("Lightbooth: keyboard off (Active Input Handling has no Input Manager); controllers and gaze work");
            }
        }

        void Gaze()
        {
            Camera eye = Camera.main;
            if (eye == null) return;
            RaycastHit hit;
            Collider target = Physics.Raycast(new Ray(eye.transform.position, eye.transform.forward), out hit, 5f) ? hit.collider : null;
            if (target != gazed) { gazed = target; gazeTime = 0f; return; }
            if (target == null) return;
            gazeTime += Time.deltaTime;
            if (gazeTime < gazeSeconds) return;
            gazeTime = float.NegativeInfinity;   // once per look: look away to press again
            if (target == sourceButton) NextSource();
            else if (target == levelButton) ToggleLevel();
        }
    }
}
