// Copies one eye of the renderer's output into an OpenXR swapchain image (one pass per
// eye, a full-screen triangle, texel for texel).
//
// The renderer's colour target is Rgba8Unorm holding sRGB-encoded values. The shader
// decodes them to linear light: an sRGB swapchain encodes them again on write (the 8-bit
// round trip is exact), and a linear swapchain (UNORM or float) is read as linear by the
// runtime, as OpenXR specifies. Depth (reversed-Z, Depth32Float) is copied unchanged
// through frag_depth, so any depth swapchain format takes it.

@group(0) @binding(0) var eye_color: texture_2d<f32>;
@group(0) @binding(1) var eye_depth: texture_depth_2d;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

fn eye_texel(position: vec4<f32>) -> vec4<f32> {
    let c = textureLoad(eye_color, vec2<i32>(position.xy), 0);
    return vec4<f32>(srgb_to_linear(clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0))), 1.0);
}

struct ColorDepth {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_color_depth(@builtin(position) position: vec4<f32>) -> ColorDepth {
    var out: ColorDepth;
    out.color = eye_texel(position);
    out.depth = clamp(textureLoad(eye_depth, vec2<i32>(position.xy), 0), 0.0, 1.0);
    return out;
}

@fragment
fn fs_color(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return eye_texel(position);
}
