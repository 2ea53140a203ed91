// The renderer's lights and tone mapping (lighting.rs), apart from the engine's frame
// uniforms: the direct light and the tone mapping read them.

struct Shading {
    // Lights per view in `lights`, the views one after the other.
    light_count: u32,
    // Linear exposure before tone mapping.
    exposure: f32,
    // Reinhard's L_white: the smallest exposed luminance mapped to white.
    white_point: f32,
    _pad0: u32,
};

// A light in one view's space. kind: 0 directional (dir = direction light travels),
// 1 point (pos = view-space position), 2 spot. radiance = colour × intensity.
struct Light {
    pos_or_dir: vec4<f32>,
    radiance: vec4<f32>,
    kind: vec4<u32>,
    // Spot lights (kind.x == 2): the cone's view-space axis, and (cos outer, ramp scale).
    spot_direction: vec4<f32>,
    cone: vec4<f32>,
};
