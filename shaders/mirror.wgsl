// The desktop window's picture: one eye image (or the mono view) drawn into a viewport
// with a full-screen triangle. The eye images already hold sRGB-encoded values, and the
// window surface is a non-sRGB format, so the values pass through unchanged.

@group(0) @binding(0) var eye_image: texture_2d<f32>;
@group(0) @binding(1) var eye_sampler: sampler;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // (0,0), (2,0), (0,2) in uv: one triangle that covers the viewport.
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSampleLevel(eye_image, eye_sampler, in.uv, 0.0).rgb, 1.0);
}
