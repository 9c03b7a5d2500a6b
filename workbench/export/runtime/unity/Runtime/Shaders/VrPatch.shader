// The patch shader of VrPatchServer: unlit, writes exactly the values VrPatchServer computed
// (Patch/PatchColour.cs: DAC/255 in a Gamma project, its sRGB decoding in a Linear project,
// so that the 8-bit eye buffer holds the DAC). No lighting, no fog, no texture, no dithering,
// no blending, depth test off; the quad's corners are already in clip space, so it covers the
// whole of each eye's view whatever the head pose and the projection.
//
// Picture, in the eye buffer's pixels (the field is the eye's render target; its centre is where
// the instrument is aimed, which the target shows):
//   _Target = 0: the patch inside a centred rectangle whose sides are _HalfSide*2 of the field's
//                (sqrt(window)), _SurroundColour outside it (a full field: _HalfSide = 0.5);
//   _Target = 1: black, white rings of radius 10, 20, 30 and 40 % of the field's smaller side,
//                2 pixels wide, and a cross through the centre, 2 pixels wide;
//   _Eye: -1 both eyes; 0 the left eye only, 1 the right eye only (the other eye black).
Shader "Hidden/VrColourWorkbench/Patch"
{
    Properties
    {
        _PatchColour ("Patch (shader values, not a colour: set by VrPatchServer)", Vector) = (0, 0, 0, 1)
        _SurroundColour ("Surround (shader values)", Vector) = (0, 0, 0, 1)
        _TargetColour ("Target lines (shader values)", Vector) = (1, 1, 1, 1)
        _HalfSide ("Half the window's side, fraction of the field", Float) = 0.5
        _Eye ("Eye: -1 both, 0 left, 1 right", Float) = -1
        _Target ("Centring target", Float) = 0
    }
    SubShader
    {
        Tags { "Queue" = "Overlay" "RenderType" = "Opaque" "IgnoreProjector" = "True" "PreviewType" = "Plane" }
        Pass
        {
            Cull Off
            ZWrite Off
            ZTest Always
            Blend Off
            Lighting Off
            Fog { Mode Off }

            CGPROGRAM
            #pragma vertex vert
            #pragma fragment frag
            #pragma target 3.5
            #pragma multi_compile_instancing
            #include "UnityCG.cginc"

            float4 _PatchColour;
            float4 _SurroundColour;
            float4 _TargetColour;
            float _HalfSide;
            float _Eye;
            float _Target;

            struct appdata
            {
                float4 vertex : POSITION;
                float2 uv : TEXCOORD0;
                UNITY_VERTEX_INPUT_INSTANCE_ID
            };

            struct v2f
            {
                float4 position : SV_POSITION;
                float2 uv : TEXCOORD0;
                UNITY_VERTEX_OUTPUT_STEREO
            };

            v2f vert(appdata v)
            {
                v2f o;
                UNITY_SETUP_INSTANCE_ID(v);
                UNITY_INITIALIZE_OUTPUT(v2f, o);
                UNITY_INITIALIZE_VERTEX_OUTPUT_STEREO(o);  // single-pass instanced / multiview: the eye's slice
                // The mesh holds clip-space corners: pass them through, at the near plane.
                o.position = float4(v.vertex.xy, UNITY_NEAR_CLIP_VALUE, 1.0);
                o.uv = v.uv;
                return o;
            }

            float4 frag(v2f i) : SV_Target
            {
                UNITY_SETUP_STEREO_EYE_INDEX_POST_VERTEX(i);
                if (_Eye >= 0.0 && abs((float)unity_StereoEyeIndex - _Eye) > 0.5)
                    return float4(0.0, 0.0, 0.0, 1.0);  // the other eye is black
                float2 fromCentre = i.uv - 0.5;  // fraction of the field
                if (_Target < 0.5)
                {
                    bool inside = abs(fromCentre.x) <= _HalfSide && abs(fromCentre.y) <= _HalfSide;
                    return inside ? _PatchColour : _SurroundColour;
                }
                // The field's size in pixels from the screen-space derivatives of uv (the quad spans
                // the render target exactly), so the lines are 2 pixels wide at any resolution.
                float2 fieldPixels = 1.0 / max(abs(float2(ddx(i.uv.x), ddy(i.uv.y))), 1e-6);
                float2 pixels = fromCentre * fieldPixels;  // from the centre, in pixels
                float smaller = min(fieldPixels.x, fieldPixels.y);
                float radius = length(pixels);
                bool line = abs(pixels.x) < 1.0 || abs(pixels.y) < 1.0;  // the cross
                [unroll] for (int ring = 1; ring <= 4; ring++)
                    line = line || abs(radius - 0.1 * ring * smaller) < 1.0;
                return line ? _TargetColour : float4(0.0, 0.0, 0.0, 1.0);
            }
            ENDCG
        }
    }
    Fallback Off
}
