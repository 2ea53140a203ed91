// Shadow maps (the Czech SSDO thesis §2.1, §5.1) and reflective shadow maps (Lin's NCTU thesis
// §3.3) of the scene's directional lights: one orthographic light-space layer per shadowed
// light, fitted to the scene (passes/shadow.rs). Shared by the light-space pass, the direct
// pass (PCF lookups) and the RSM gather. Nothing here binds a resource.

// One shadowed directional light (mirrors `ShadowLightUniform` in passes/shadow.rs).
struct ShadowLight {
    // Light clip from the scene's anchor frame: x, y in [-1, 1] across the map (y up),
    // z = depth in [0, 1], 0 nearest the light. Orthographic, so w = 1.
    clip_from_anchored: mat4x4<f32>,
    // Light view from the anchor frame, in metres: rigid, looking down −z along the
    // light's travel, origin at the map's centre on its near (light-side) plane.
    view_from_anchored: mat4x4<f32>,
    // rgb: colour × intensity, the irradiance on a surface facing the light.
    radiance: vec4<f32>,
    // x: texel size p in metres; y: depth range in metres (light view z = −depth · y);
    // z: half the map's side in metres (the map spans x, y in [−z, z]).
    extent: vec4<f32>,
    // x: the light's index in the scene's light list (and in `lights` of common.wgsl).
    index: vec4<u32>,
};

struct Shadows {
    // Shadowed lights, one map layer each; 0 turns every lookup off.
    count: u32,
    // Texels along each side of the square maps.
    size: u32,
    _pad0: u32,
    _pad1: u32,
    lights: array<ShadowLight, 4>,
};

// tan α is clamped here (α ≈ 83°): beyond it the bias would grow without bound while the
// light it protects, cos α < 0.12 of the full irradiance, hardly shows.
const SHADOW_MAX_TAN: f32 = 8.0;
// Depth units added to every comparison: a few ulps of Depth32Float near 1.
const SHADOW_MIN_BIAS: f32 = 1e-6;

// Anchored (scene) position and direction of a view-space point or vector of `eye`:
// view_from_anchored is rigid, so its inverse is the transposed rotation.
fn anchored_from_view_point(eye: Eye, v: vec3<f32>) -> vec3<f32> {
    let m = eye.view_from_anchored;
    let r = mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz);
    return transpose(r) * (v - m[3].xyz);
}

fn anchored_from_view_vector(eye: Eye, v: vec3<f32>) -> vec3<f32> {
    let m = eye.view_from_anchored;
    return transpose(mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz)) * v;
}

// Fraction of `light` (map layer `layer`, `size` texels a side) reaching the surface at
// anchored position `pa` with unit normal `na` (facing the light): 3×3 PCF, taps one
// texel apart, each a bilinear 2×2 hardware comparison (the Czech SSDO thesis: "3x3 … simply
// averaged … bilinear filtering for shadow maps").
//
// Bias (the Czech SSDO thesis, b = p/2 · tan α): a comparison stands for the patch of texels it
// reads. Each tap compares against the receiver's tangent plane extrapolated to the tap (so the
// 3×3 spread adds no acne), and its bilinear 2×2 reads texel centres up to one texel away
// along each axis, a patch of diagonal p' = 2√2 p; b = p'/2 · tan α = √2 p tan α keeps a
// lit plane at any orientation from shadowing itself.
fn pcf_visibility(
    map: texture_depth_2d_array,
    cmp: sampler_comparison,
    light: ShadowLight,
    layer: u32,
    size: u32,
    pa: vec3<f32>,
    na: vec3<f32>,
) -> f32 {
    let clip = light.clip_from_anchored * vec4<f32>(pa, 1.0);
    let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    // Outside the fitted volume nothing casts (and NaN positions fail every test: lit).
    if (!(all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) && clip.z >= 0.0 && clip.z <= 1.0)) {
        return 1.0;
    }
    let p = light.extent.x;
    let range = light.extent.y;
    // The normal in light view (+z towards the light); facing away it is lit by nobody.
    let nl = (light.view_from_anchored * vec4<f32>(na, 0.0)).xyz;
    let cos_a = clamp(nl.z, 1.0 / sqrt(1.0 + SHADOW_MAX_TAN * SHADOW_MAX_TAN), 1.0);
    let tan_a = sqrt(max(1.0 - cos_a * cos_a, 0.0)) / cos_a;
    // Receiver plane: light view z changes by g per metre across the map (|g| = tan α).
    var g = -nl.xy / cos_a;
    let g_len = length(g);
    if (g_len > SHADOW_MAX_TAN) {
        g *= SHADOW_MAX_TAN / g_len;
    }
    // Depth per texel step: +u is +x, +v is −y; depth = −z / range.
    let depth_du = -g.x * p / range;
    let depth_dv = g.y * p / range;
    let bias = 1.41421356 * p * tan_a / range + SHADOW_MIN_BIAS;
    let texel = 1.0 / f32(size);
    var lit = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let reference = clip.z + depth_du * f32(dx) + depth_dv * f32(dy) - bias;
            let at = uv + vec2<f32>(f32(dx), f32(dy)) * texel;
            lit += textureSampleCompareLevel(map, cmp, at, i32(layer), reference);
        }
    }
    return lit / 9.0;
}
