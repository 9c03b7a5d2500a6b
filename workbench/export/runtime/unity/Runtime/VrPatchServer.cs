// VrPatchServer: the headset side of the workbench's patch protocol (vr-workbench-patch/1).
//
// Add it to any GameObject of a scene that renders to the headset. While it is enabled it
// listens on its address and port (loopback 127.0.0.1:47800 by default) for the workbench
// (`measure --display tcp:127.0.0.1:47800`) and shows each requested patch in the headset:
//
// - the network runs on worker threads (Patch/PatchServerCore.cs); Update only empties a queue,
//   so the render loop never waits on a socket; one client at a time, a second one is told
//   who is being served and closed; a client that vanishes is logged, not an error;
// - each picture is drawn by a dedicated camera (depth above every other camera, both eyes)
//   that sees only one layer (patchLayer), where a quad given in clip space covers the whole
//   of each eye's view whatever the head pose; the camera clears to black and has no HDR, no
//   MSAA, no dynamic resolution and no post-processing (a fresh URP camera has none; the
//   built-in pipeline's post-processing stack lives on other cameras), and, by default, the
//   other cameras are switched off while patches are shown;
// - the shader (Shaders/VrPatch.shader, unlit, no fog, no lighting, no dithering) writes the
//   value whose 8-bit framebuffer value is the DAC: d/255 in a Gamma project (UNORM eye
//   buffer), the sRGB-decoded value in a Linear project (the sRGB eye buffer encodes it back);
//   Patch/PatchColour.cs holds this arithmetic, checked for all 256 values of each channel, in
//   float32 and half, by the workbench;
// - the reply is sent only when a frame showing the picture has been presented (see
//   ReplyOncePresented for how that is known and what the runtime may still do afterwards).
using System;
using System.Collections;
using System.Net.Sockets;
using System.Reflection;
using UnityEngine;
using VrColourWorkbench.Patch;

namespace VrColourWorkbench
{
    [DisallowMultipleComponent]
    [AddComponentMenu("VR Colour Workbench/VR Patch Server")]
    public sealed class VrPatchServer : MonoBehaviour, IPatchPresenter
    {
        [Header("Network")]
        [Tooltip("Address to listen on. Keep loopback (127.0.0.1) unless the workbench runs on another machine.")]
        [SerializeField] string address = "127.0.0.1";

        [Tooltip("TCP port the workbench connects to: measure --display tcp:ADDRESS:PORT.")]
        [SerializeField] int port = 47800;

        [Tooltip("What the hello reply names as the display (it goes into the workbench's journal); empty: Unity version and XR device.")]
        [SerializeField] string displayName = "";

        [Tooltip("Drop a client silent this long, in seconds. The workbench is silent while the instrument measures (minutes for a dark patch): keep 600 or more.")]
        [SerializeField] float idleTimeoutSeconds = 600f;

        [Tooltip("Answer a patch with an error if no frame showing it was presented within this many seconds (the workbench waits 10 s).")]
        [SerializeField] float presentTimeoutSeconds = 5f;

        [Header("Drawing")]
        [Tooltip("The layer only the patch camera sees (pick one no other object uses).")]
        [Range(0, 31)]
        [SerializeField] int patchLayer = 31;

        [Tooltip("Frames rendered after the first frame showing a patch before the reply (1: that frame has surely been submitted to the compositor; more for slow panels).")]
        [Range(1, 10)]
        [SerializeField] int framesAfterPresent = 1;

        [Tooltip("Switch the other cameras off while patches are shown (nothing else, e.g. a UI overlay camera, can draw over them).")]
        [SerializeField] bool disableOtherCameras = true;

        [Tooltip("Keep rendering when the application loses focus (the workbench's terminal has the focus during a run).")]
        [SerializeField] bool runInBackground = true;

        const string ShaderName = "Hidden/VrColourWorkbench/Patch";

        PatchServerCore core;
        Camera patchCamera;
        GameObject quad;
        Material material;
        Camera[] disabledCameras = new Camera[0];

        /// <summary>Where the server listens while enabled (the port actually bound when 0 was asked).</summary>
        public string Endpoint { get { return core != null && core.LocalEndpoint != null ? "tcp:" + core.LocalEndpoint : "(not listening)"; } }

        void OnEnable()
        {
            if (runInBackground) Application.runInBackground = true;
            if (QualitySettings.activeColorSpace != ColorSpace.Linear)
                Debug.LogWarning("VrPatchServer: this project uses the Gamma colour space. The patches are written to the "
                                 + "eye buffer as DAC/255, but an OpenXR runtime treats a UNORM (non-sRGB) swapchain as linear "
                                 + "and encodes it again for the panel; use the Linear colour space (Project Settings > Player) "
                                 + "unless you have checked what your runtime does with Gamma projects.");
            var options = new PatchServerOptions
            {
                DisplayName = string.IsNullOrEmpty(displayName)
                    ? "Unity " + Application.unityVersion + " on " + XrDeviceName() + " (VrPatchServer)"
                    : displayName,
                IdleTimeoutS = idleTimeoutSeconds,
                PresentTimeoutS = presentTimeoutSeconds,
            };
            core = new PatchServerCore(options, message => Debug.Log("VrPatchServer: " + message));
            try
            {
                core.Start(address, port);
                Debug.Log("VrPatchServer: listening on " + Endpoint + " (" + PatchProtocol.Name + ")");
            }
            catch (Exception error) when (error is SocketException || error is FormatException)
            {
                Debug.LogError("VrPatchServer: cannot listen on " + address + ":" + port + " (" + error.Message
                               + "); choose another port, or close what uses it");
                core = null;
            }
        }

        void Update()
        {
            if (core != null) core.DispatchPending(this);  // never blocks: the network runs on worker threads
        }

        void OnDisable()
        {
            if (core != null) core.Stop();
            core = null;
            StopAllCoroutines();
            HidePatch();
            if (quad != null) Destroy(quad);
            if (patchCamera != null) Destroy(patchCamera.gameObject);
            if (material != null) Destroy(material);
            quad = null;
            patchCamera = null;
            material = null;
        }

        static string XrDeviceName()
        {
            string device = UnityEngine.XR.XRSettings.loadedDeviceName;
            return string.IsNullOrEmpty(device) ? "no XR device" : device;
        }

        /// <summary>IPatchPresenter: called on the main thread by PatchServerCore.DispatchPending.</summary>
        public void Present(PatchCommand command, PatchPresentation presentation)
        {
            if (command.Kind == PatchCommandKind.ClientLeft)
            {
                HidePatch();  // back to the application's own picture
                presentation.Presented();
                return;
            }
            EnsurePatchCamera();
            bool linear = QualitySettings.activeColorSpace == ColorSpace.Linear;
            float[] patch = PatchColour.ShaderRgba(command.R, command.G, command.B, linear);
            float[] surround = PatchColour.ShaderRgba(command.SurroundR, command.SurroundG, command.SurroundB, linear);
            float[] white = PatchColour.ShaderRgba(255, 255, 255, linear);
            // SetVector passes the floats unchanged (SetColor would convert gamma to linear in a Linear project).
            material.SetVector("_PatchColour", new Vector4(patch[0], patch[1], patch[2], 1f));
            material.SetVector("_SurroundColour", new Vector4(surround[0], surround[1], surround[2], 1f));
            material.SetVector("_TargetColour", new Vector4(white[0], white[1], white[2], 1f));
            material.SetFloat("_HalfSide", (float)(0.5 * Math.Sqrt(command.Window)));
            material.SetFloat("_Eye", command.Eye == PatchEye.Left ? 0f : command.Eye == PatchEye.Right ? 1f : -1f);
            material.SetFloat("_Target", command.Kind == PatchCommandKind.Target ? 1f : 0f);
            ShowPatch();
            StartCoroutine(ReplyOncePresented(presentation));
        }

        /// <summary>
        /// Replies once a frame showing the picture has been presented to the VR compositor.
        /// </summary>
        /// <remarks>
        /// How this is known. Present() runs in Update of frame N, so frame N is the first frame drawn
        /// with the new material values. WaitForEndOfFrame resumes when frame N's rendering has been
        /// issued on the main thread; its GPU work and its submission to the compositor (OpenXR
        /// xrEndFrame, OpenVR IVRCompositor::Submit) happen on Unity's render thread, which may run up
        /// to a frame behind. Unity's main thread cannot finish issuing frame N+1 before the render
        /// thread has finished frame N, and in XR frame N+1 only starts once the runtime's frame
        /// pacing (xrWaitFrame / WaitGetPoses) has let it. So at the end of frame N+1
        /// (framesAfterPresent = 1) frame N has been submitted: the compositor holds the patch and shows
        /// it at its next refresh, and every later frame shows it too. Raise framesAfterPresent for
        /// panels that need time to settle. If the application is not rendering (paused, the
        /// runtime's dashboard has the focus), no frame ends and the core answers ok:false after
        /// presentTimeoutSeconds.
        ///
        /// What the runtime may still do after that, outside this application: it composites the
        /// eye buffers (sRGB-decoded to linear when the swapchain is sRGB; a UNORM swapchain is read
        /// as linear values by OpenXR), applies the lens distortion and chromatic-aberration
        /// correction (a uniform field stays uniform at its centre), may reproject (timewarp) the
        /// frame, and converts to the panel through its own colour pipeline: OpenXR
        /// XR_FB_color_space on Meta runtimes maps from the chosen colour space (choose
        /// XR_COLOR_SPACE_UNMANAGED_FB for the panel's native primaries), SteamVR applies its
        /// colour settings (Settings > Video > colour adjustments: keep them neutral) and the
        /// headset's factory calibration, Varjo Base and Pimax software have colour and brightness
        /// options. The workbench characterizes the chain as it is set during the measurement: keep
        /// the same settings when the calibrated content runs.
        /// </remarks>
        IEnumerator ReplyOncePresented(PatchPresentation presentation)
        {
            yield return new WaitForEndOfFrame();  // frame N (the first with the picture) issued
            for (int frame = 0; frame < framesAfterPresent; frame++)
            {
                yield return null;                 // frame N+1 begins: the runtime's frame pacing let it
                yield return new WaitForEndOfFrame();
            }
            presentation.Presented();
        }

        void EnsurePatchCamera()
        {
            if (material == null)
            {
                var shader = Shader.Find(ShaderName);
                if (shader == null)
                    throw new InvalidOperationException("shader " + ShaderName + " not found; add it to Project Settings > Graphics > "
                                                        + "Always Included Shaders (a build strips shaders nothing references)");
                material = new Material(shader) { name = "VrPatchServer patch" };
            }
            if (patchCamera == null)
            {
                var cameraObject = new GameObject("VrPatchServer camera");
                cameraObject.transform.SetParent(transform, false);
                patchCamera = cameraObject.AddComponent<Camera>();
                patchCamera.clearFlags = CameraClearFlags.SolidColor;
                patchCamera.backgroundColor = new Color(0f, 0f, 0f, 1f);
                patchCamera.cullingMask = 1 << patchLayer;
                patchCamera.depth = 1000f;  // after every other camera
                patchCamera.allowHDR = false;  // an 8-bit eye buffer, no float intermediate, no tonemapping
                patchCamera.allowMSAA = false;
                patchCamera.allowDynamicResolution = false;
                patchCamera.useOcclusionCulling = false;
                patchCamera.nearClipPlane = 0.01f;
                patchCamera.farClipPlane = 10f;
                patchCamera.stereoTargetEye = StereoTargetEyeMask.Both;
                patchCamera.enabled = false;
                DisablePipelinePostProcessing(cameraObject);
            }
            if (quad == null)
            {
                quad = new GameObject("VrPatchServer patch quad");
                quad.layer = patchLayer;
                quad.transform.SetParent(patchCamera.transform, false);
                quad.transform.localPosition = new Vector3(0f, 0f, 1f);
                var mesh = new Mesh { name = "VrPatchServer clip-space quad" };
                // Clip-space corners: the vertex shader passes them through, so the quad covers each eye's whole view.
                mesh.vertices = new[] { new Vector3(-1f, -1f, 0f), new Vector3(1f, -1f, 0f), new Vector3(1f, 1f, 0f), new Vector3(-1f, 1f, 0f) };
                mesh.uv = new[] { new Vector2(0f, 0f), new Vector2(1f, 0f), new Vector2(1f, 1f), new Vector2(0f, 1f) };
                mesh.triangles = new[] { 0, 2, 1, 0, 3, 2 };
                mesh.bounds = new Bounds(Vector3.zero, new Vector3(1e6f, 1e6f, 1e6f));  // never frustum-culled
                quad.AddComponent<MeshFilter>().sharedMesh = mesh;
                var renderer = quad.AddComponent<MeshRenderer>();
                renderer.sharedMaterial = material;
            }
        }

        /// <summary>
        /// URP adds UniversalAdditionalCameraData to a camera with post-processing, anti-aliasing and
        /// dithering off; set them off explicitly (by reflection: this package does not depend on URP).
        /// HDRP always runs its exposure and tonemapping: use the built-in pipeline or URP for patches.
        /// </summary>
        static void DisablePipelinePostProcessing(GameObject cameraObject)
        {
            foreach (var component in cameraObject.GetComponents<Component>())
            {
                if (component == null) continue;
                Type type = component.GetType();
                if (type.Name == "HDAdditionalCameraData")
                    Debug.LogWarning("VrPatchServer: HDRP applies exposure and tonemapping to every camera; the patches "
                                     + "are not exact DAC values there (use the built-in render pipeline or URP)");
                if (type.Name != "UniversalAdditionalCameraData") continue;
                SetIfPresent(component, "renderPostProcessing", false);
                SetIfPresent(component, "dithering", false);
                SetIfPresent(component, "stopNaN", false);
                PropertyInfo antialiasing = type.GetProperty("antialiasing");
                if (antialiasing != null && antialiasing.CanWrite)
                    antialiasing.SetValue(component, Enum.ToObject(antialiasing.PropertyType, 0), null);  // None
            }
        }

        static void SetIfPresent(object target, string property, object value)
        {
            PropertyInfo info = target.GetType().GetProperty(property);
            if (info != null && info.CanWrite) info.SetValue(target, value, null);
        }

        void ShowPatch()
        {
            if (patchCamera.enabled) return;
            if (disableOtherCameras)
            {
                var others = new System.Collections.Generic.List<Camera>();
                foreach (var camera in Camera.allCameras)
                {
                    if (camera == patchCamera || !camera.enabled) continue;
                    camera.enabled = false;
                    others.Add(camera);
                }
                disabledCameras = others.ToArray();
            }
            patchCamera.enabled = true;
        }

        void HidePatch()
        {
            if (patchCamera != null) patchCamera.enabled = false;
            foreach (var camera in disabledCameras)
            {
                if (camera != null) camera.enabled = true;
            }
            disabledCameras = new Camera[0];
        }
    }
}
