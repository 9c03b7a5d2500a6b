// The Lightbooth sample's surfaces: frame buffer (linear) = albedo (linear) x the bundle's light
// colour (linear, lights.json "linear", set by LightboothBootstrap as _VrLightLinear): the engine
// model the bundle's level-1 and level-2 numbers assume. No ambient, no specular, no tonemapping,
// no dependence on the surface's angle to the lamp. Built-in pipeline and URP (a plain unlit
// pass); single-pass instanced stereo supported. In a Linear project the sampler decodes the
// sRGB albedo and the frame buffer encodes the result; in a Gamma project neither happens, so
// the shader decodes and encodes itself (exact sRGB), and the bytes are the same.
// In Resources/ so that Shader.Find finds it in a player build.
Shader "VrColourWorkbench/BoothSurface"
{
    Properties
    {
        _MainTex ("Albedo (sRGB)", 2D) = "white" {}
        _VrLightLinear ("Light colour (linear)", Vector) = (1, 1, 1, 1)
    }
    SubShader
    {
        Tags { "RenderType" = "Opaque" "Queue" = "Geometry" }
        Pass
        {
            CGPROGRAM
            #pragma vertex vert
            #pragma fragment frag
            #pragma multi_compile_instancing
            #include "UnityCG.cginc"

            sampler2D _MainTex;
            float4 _MainTex_ST;
            float4 _VrLightLinear;

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
                UNITY_INITIALIZE_VERTEX_OUTPUT_STEREO(o);
                o.position = UnityObjectToClipPos(v.vertex);
                o.uv = TRANSFORM_TEX(v.uv, _MainTex);
                return o;
            }

            float4 frag(v2f i) : SV_Target
            {
                UNITY_SETUP_STEREO_EYE_INDEX_POST_VERTEX(i);
                float3 albedo = tex2D(_MainTex, i.uv).rgb;
            #if defined(UNITY_COLORSPACE_GAMMA)
                float3 lit = float3(GammaToLinearSpaceExact(albedo.r), GammaToLinearSpaceExact(albedo.g),
                                    GammaToLinearSpaceExact(albedo.b)) * _VrLightLinear.rgb;
                return float4(LinearToGammaSpaceExact(lit.r), LinearToGammaSpaceExact(lit.g),
                              LinearToGammaSpaceExact(lit.b), 1.0);
            #else
                return float4(albedo * _VrLightLinear.rgb, 1.0);
            #endif
            }
            ENDCG
        }
    }
}
