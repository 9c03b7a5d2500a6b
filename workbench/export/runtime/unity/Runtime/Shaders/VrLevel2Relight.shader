// ShaderLab wrapper of Level2Relight.hlsl for Unity (any render pipeline): a full-screen
// triangle (3 vertices, no mesh) and the level-2 relight pixel shader.
Shader "Hidden/VrColourWorkbench/Level2Relight"
{
    SubShader
    {
        Cull Off ZWrite Off ZTest Always Blend Off
        Pass
        {
            HLSLPROGRAM
            #pragma target 4.5
            #pragma vertex VrFullScreenTriangle
            #pragma fragment main
            #include "Level2Relight.hlsl"
            ENDHLSL
        }
    }
}
