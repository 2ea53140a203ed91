// Shared by every pass: the frame uniforms, the lights and the one depth → view-space
// position helper (mirrors `stereo::view_position_from_depth`).

struct Eye {
    // Clip from the scene's anchor frame (geometry is stored relative to an f64 anchor).
    clip_from_anchored: mat4x4<f32>,
    // View from the anchor frame (normals use its rotation).
    view_from_anchored: mat4x4<f32>,
    // World from view, rotation only (environment lookups).
    world_from_view: mat4x4<f32>,
    // tan(left), tan(right), tan(up), tan(down) of the eye's asymmetric frustum.
    tangents: vec4<f32>,
};

struct Frame {
    eyes: array<Eye, 2>,
    size: vec2<u32>,
    layers: u32,
    light_count: u32,
    near: f32,
    exposure: f32,
    white_point: f32,
    has_environment: u32,
    // Irradiance SH9 (already scaled by the environment intensity), rgb in xyz.
    irradiance_sh: array<vec4<f32>, 9>,
};

// A light in one eye's view space. kind: 0 directional (dir = direction light travels),
// 1 point (pos = view-space position). radiance = colour × intensity.
struct Light {
    pos_or_dir: vec4<f32>,
    radiance: vec4<f32>,
    kind: vec4<u32>,
};

const PI: f32 = 3.14159265358979;

// Centre of pixel `p` in 0..1 texture coordinates (origin top-left).
fn pixel_uv(p: vec2<u32>, size: vec2<u32>) -> vec2<f32> {
    return (vec2<f32>(p) + vec2<f32>(0.5)) / vec2<f32>(size);
}

// View-space position seen at `uv` with reversed-Z infinite-far depth `depth` (> 0).
// distance = near / depth; x and y follow the frustum tangents, so no inverse matrix
// costs precision.
fn view_position_from_depth(uv: vec2<f32>, depth: f32, tangents: vec4<f32>, near: f32) -> vec3<f32> {
    let distance = near / max(depth, 1e-30);
    let tan_x = mix(tangents.x, tangents.y, uv.x);
    let tan_y = mix(tangents.z, tangents.w, uv.y);
    return vec3<f32>(tan_x * distance, tan_y * distance, -distance);
}

// View-space direction through `uv` (unit length).
fn view_ray(uv: vec2<f32>, tangents: vec4<f32>) -> vec3<f32> {
    return normalize(vec3<f32>(mix(tangents.x, tangents.y, uv.x), mix(tangents.z, tangents.w, uv.y), -1.0));
}

// Replaces NaN and ±Inf by 0 and clamps to the f16 range, so no pass writes a value
// a half-float target cannot hold.
fn finite_or_zero3(v: vec3<f32>) -> vec3<f32> {
    let ok = (v == v) & (abs(v) <= vec3<f32>(3.0e38));
    return clamp(select(vec3<f32>(0.0), v, ok), vec3<f32>(-65504.0), vec3<f32>(65504.0));
}
