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

// The panel's buffer view: one eye's buffer shown texel for texel (nearest), so that
// half-resolution AO shows its own pixels. Each entry point uses one of these bindings.
@group(0) @binding(2) var float_buffer: texture_2d<f32>;
@group(0) @binding(3) var depth_buffer: texture_depth_2d;

fn buffer_texel(size: vec2<u32>, uv: vec2<f32>) -> vec2<i32> {
    return vec2<i32>(min(vec2<u32>(max(uv, vec2<f32>(0.0)) * vec2<f32>(size)), size - 1u));
}

// Occlusion (alpha) as grey, written as is, like `vrao render --debug`'s ao images.
@fragment
fn fs_occlusion(in: VertexOut) -> @location(0) vec4<f32> {
    let texel = buffer_texel(textureDimensions(float_buffer), in.uv);
    let ao = clamp(textureLoad(float_buffer, texel, 0).a, 0.0, 1.0);
    return vec4<f32>(vec3<f32>(ao), 1.0);
}

// Occlusion of a single-channel AO chain (R16Float: the AO in red) as grey.
@fragment
fn fs_occlusion_red(in: VertexOut) -> @location(0) vec4<f32> {
    let texel = buffer_texel(textureDimensions(float_buffer), in.uv);
    let ao = clamp(textureLoad(float_buffer, texel, 0).r, 0.0, 1.0);
    return vec4<f32>(vec3<f32>(ao), 1.0);
}

// View-space normals, xyz from [-1, 1] to [0, 1].
@fragment
fn fs_normals(in: VertexOut) -> @location(0) vec4<f32> {
    let texel = buffer_texel(textureDimensions(float_buffer), in.uv);
    let n = clamp(textureLoad(float_buffer, texel, 0).xyz, vec3<f32>(-1.0), vec3<f32>(1.0));
    return vec4<f32>(n * 0.5 + 0.5, 1.0);
}

// Reversed-Z depth with an infinite far plane stores near / distance, so -ln(depth) is
// ln(distance / near): shown from white at the near plane to dark at 2000 near planes
// (100 m at the default 5 cm), black for the sky (depth 0).
@fragment
fn fs_depth(in: VertexOut) -> @location(0) vec4<f32> {
    let texel = buffer_texel(textureDimensions(depth_buffer), in.uv);
    let d = textureLoad(depth_buffer, texel, 0);
    let v = select(0.0, 1.0 - 0.85 * clamp(-log(d) / log(2000.0), 0.0, 1.0), d > 0.0);
    return vec4<f32>(vec3<f32>(v), 1.0);
}
