// Level-2 relight of a VR colour workbench bundle, HLSL (Shader Model 5; Unity, D3D11/12, Vulkan).
//
// The same arithmetic as level2_relight.frag: render a full-screen pass into an
// RGBA8 UNORM target of the cube's size (not sRGB: the texels are already
// sRGB-encoded); alpha is 0 where the light cannot carry the texel, else 1.
// Entry points: VrFullScreenTriangle (vertex: a full-screen triangle from
// SV_VertexID, draw 3 vertices, no mesh) and main (pixel). In Unity,
// VrLevel2Relight.shader wraps them in a pass; VrColourBundle.BindLevel2 sets
// the inputs and VrColourBundle.Relight draws the pass.
#define MAX_LAYERS 16

Texture2DArray<float4> _VrCoefficients : register(t0);   // RGBA16F, ceil(C / 4) layers
Texture2D<float> _VrThresholds : register(t1);           // R32F 255 x 3
Texture2D<float> _VrTexelTable : register(t2);           // R32F 256 x 3, values 0..255
Texture3D<float4> _VrDriveCorrection : register(t3);     // RGBA32F size^3 (rgb used)
Texture2D<float> _VrCells : register(t4);                // R32F 4096 x 3: DAC lower bound per cell of u

cbuffer VrLevel2 : register(b0)
{
    float4 _VrMatrixRows[3 * MAX_LAYERS]; // [3 * layer + output channel]
    float4 _VrDriveOffset;                // xyz
    float4 _VrCorrectionDomain;           // x = low, y = high
    int _VrLayers;
    int _VrCorrectionSize;                // 0: no correction table
    int _VrPad0;
    int _VrPad1;
    int4 _VrUnreachableDac;               // xyz
};

float3 VrCorrected(float3 drive)
{
    float n1 = (float)(_VrCorrectionSize - 1);
    float3 position = saturate((drive - _VrCorrectionDomain.x)
                               / (_VrCorrectionDomain.y - _VrCorrectionDomain.x)) * n1;
    int3 base = min((int3)floor(position), int3(_VrCorrectionSize - 2, _VrCorrectionSize - 2,
                                                _VrCorrectionSize - 2));
    float3 f = position - (float3)base;
    float3 result = float3(0.0, 0.0, 0.0);
    [unroll] for (int db = 0; db < 2; ++db)
        [unroll] for (int dg = 0; dg < 2; ++dg)
            [unroll] for (int dr = 0; dr < 2; ++dr)
            {
                float w = (db == 1 ? f.z : 1.0 - f.z) * (dg == 1 ? f.y : 1.0 - f.y)
                        * (dr == 1 ? f.x : 1.0 - f.x);
                result += w * _VrDriveCorrection.Load(int4(base + int3(dr, dg, db), 0)).rgb;
            }
    return result;
}

int VrDacLevel(int channel, float u)
{
    // how many of the channel's thresholds are <= u: from the cell's lower bound, step up
    uint cellCount, rows;
    _VrCells.GetDimensions(cellCount, rows);
    int level = (int)_VrCells.Load(int3((int)(u * (float)(cellCount - 1)), channel, 0));
    [loop] while (level < 255 && _VrThresholds.Load(int3(level, channel, 0)) <= u) ++level;
    return level;
}

float4 VrLevel2Relight(int2 xy)
{
    float3 drive = _VrDriveOffset.xyz;
    [loop] for (int layer = 0; layer < _VrLayers; ++layer)
    {
        float4 c = _VrCoefficients.Load(int4(xy, layer, 0));
        drive += float3(dot(_VrMatrixRows[3 * layer], c), dot(_VrMatrixRows[3 * layer + 1], c),
                        dot(_VrMatrixRows[3 * layer + 2], c));
    }
    if (_VrCorrectionSize > 0) drive = VrCorrected(drive);
    float3 u = sqrt(saturate(drive));
    int3 dac = int3(VrDacLevel(0, u.r), VrDacLevel(1, u.g), VrDacLevel(2, u.b));
    float3 value = float3(_VrTexelTable.Load(int3(dac.r, 0, 0)), _VrTexelTable.Load(int3(dac.g, 1, 0)),
                          _VrTexelTable.Load(int3(dac.b, 2, 0)));
    bool unreachable = any(dac >= _VrUnreachableDac.xyz);
    return float4(value / 255.0, unreachable ? 0.0 : 1.0);
}

float4 VrFullScreenTriangle(uint id : SV_VertexID) : SV_Position
{
    float2 corner = float2((float)((id << 1) & 2), (float)(id & 2));
    return float4(corner * 2.0 - 1.0, 0.0, 1.0);
}

float4 main(float4 position : SV_Position) : SV_Target
{
    return VrLevel2Relight((int2)position.xy);
}
