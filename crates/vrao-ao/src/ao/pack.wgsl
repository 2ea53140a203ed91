// The engine's output in a single-channel format: one full-screen triangle per view
// layer copies the final AO's alpha (the ambient visibility) into the red channel of an
// R16Float or R8Unorm attachment (render attachments take both formats everywhere;
// storage writes to them are optional in wgpu).

struct PackLayer {
    layer: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var final_ao: texture_2d_array<f32>;
@group(0) @binding(1) var<uniform> pack: PackLayer;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let visibility = textureLoad(final_ao, vec2<i32>(position.xy), i32(pack.layer), 0).a;
    return vec4<f32>(visibility, 0.0, 0.0, 1.0);
}
