#version 430
// Level-2 relight of a VR colour workbench bundle (one fragment per texel).
//
// Render a full-screen pass into an RGBA8 (UNORM) target of the cube's size; the
// result is the texture the engine uploads (sRGB-encoded values in an UNORM target:
// do not use an sRGB target, the texels are already encoded). Alpha is 0 where
// the light cannot carry the texel (design §2), else 1.
//
// Per texel: drive = matrix * channels + offset; optional drive correction (3D
// table, trilinear); u = sqrt(clamp(drive, 0, 1)); DAC = number of the channel's
// 255 thresholds <= u (from a per-cell lower bound); texel = texel_table[channel][DAC].
#define MAX_LAYERS 16

uniform sampler2DArray coefficients;   // RGBA16F, layers = ceil(C / 4), from coefficients.bin
uniform sampler2D thresholds;          // R32F, 255 x 3 (row = channel), display_inverse.json
uniform sampler2D cells;               // R32F, 4096 x 3: lower bound of the DAC per cell of u
uniform sampler2D texel_table;         // R32F, 256 x 3 (row = channel), values 0..255
uniform sampler3D drive_correction;    // RGB32F, size^3, display_drive_correction.bin
uniform int layers;
uniform vec4 matrix_rows[3 * MAX_LAYERS]; // [3 * layer + output channel]: 4 channels' weights
uniform vec3 drive_offset;
uniform int correction_size;           // 0: no correction table
uniform vec2 correction_domain;
uniform ivec3 unreachable_dac;

out vec4 texel;

vec3 corrected(vec3 drive) {
    float n1 = float(correction_size - 1);
    vec3 position = clamp((drive - correction_domain.x) / (correction_domain.y - correction_domain.x),
                          0.0, 1.0) * n1;
    ivec3 base = min(ivec3(floor(position)), ivec3(correction_size - 2));
    vec3 f = position - vec3(base);
    vec3 result = vec3(0.0);
    for (int db = 0; db < 2; ++db)
        for (int dg = 0; dg < 2; ++dg)
            for (int dr = 0; dr < 2; ++dr) {
                float w = (db == 1 ? f.z : 1.0 - f.z) * (dg == 1 ? f.y : 1.0 - f.y)
                        * (dr == 1 ? f.x : 1.0 - f.x);
                result += w * texelFetch(drive_correction, base + ivec3(dr, dg, db), 0).rgb;
            }
    return result;
}

int dac_level(int channel, float u) {
    // how many of the channel's thresholds are <= u: from the cell's lower bound, step up
    int cell_count = textureSize(cells, 0).x;
    int level = int(texelFetch(cells, ivec2(int(u * float(cell_count - 1)), channel), 0).r);
    while (level < 255 && texelFetch(thresholds, ivec2(level, channel), 0).r <= u) ++level;
    return level;
}

void main() {
    ivec2 xy = ivec2(gl_FragCoord.xy);
    vec3 drive = drive_offset;
    for (int layer = 0; layer < layers; ++layer) {
        vec4 c = texelFetch(coefficients, ivec3(xy, layer), 0);
        drive += vec3(dot(matrix_rows[3 * layer], c), dot(matrix_rows[3 * layer + 1], c),
                      dot(matrix_rows[3 * layer + 2], c));
    }
    if (correction_size > 0) drive = corrected(drive);
    vec3 u = sqrt(clamp(drive, 0.0, 1.0));
    ivec3 dac = ivec3(dac_level(0, u.r), dac_level(1, u.g), dac_level(2, u.b));
    vec3 value = vec3(texelFetch(texel_table, ivec2(dac.r, 0), 0).r,
                      texelFetch(texel_table, ivec2(dac.g, 1), 0).r,
                      texelFetch(texel_table, ivec2(dac.b, 2), 0).r);
    bool unreachable = any(greaterThanEqual(dac, unreachable_dac));
    texel = vec4(value / 255.0, unreachable ? 0.0 : 1.0);
}
