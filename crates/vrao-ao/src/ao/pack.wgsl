// The engine's output in a single-channel format: one full-screen triangle per view
// layer copies the final AO's alpha (the ambient visibility) into the red channel of an
// R16Float or R8Unorm attachment (render attachments take both formats everywhere;
// storage writes to them are optional in wgpu), or the whole texel into an Rgba16Float
// one; either way AO 1 where the host's exclusion mask says a pixel receives none.

struct PackLayer {
    layer: u32,
    // The host mask's bits of pixels that receive no AO (0: no mask).
    receive_none: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var final_ao: texture_2d_array<f32>;
@group(0) @binding(1) var<uniform> pack: PackLayer;
// The host's exclusion mask, or a placeholder of zeros.
@group(0) @binding(2) var host_mask: texture_2d_array<u32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// The final AO at `p`, its visibility 1 where the mask says the pixel receives none.
fn final_at(p: vec2<i32>) -> vec4<f32> {
    var texel = chain_value(textureLoad(final_ao, p, i32(pack.layer), 0));
    if (pack.receive_none != 0u && (textureLoad(host_mask, p, i32(pack.layer), 0).r & pack.receive_none) != 0u) {
        texel.a = 1.0;
    }
    return texel;
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(final_at(vec2<i32>(position.xy)).a, 0.0, 0.0, 1.0);
}

@fragment
fn fs_rgba(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return final_at(vec2<i32>(position.xy));
}
