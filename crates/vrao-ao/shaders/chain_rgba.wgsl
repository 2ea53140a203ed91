// The AO chain's texel when it carries light (SSDO), or on a device that cannot write
// R16Float storage: rgb light, a AO (Rgba16Float, 8 bytes). The first file of every
// kernel; chain_scalar.wgsl is the other layout with the same names.
alias ChainTarget = texture_storage_2d_array<rgba16float, write>;

// A chain texel as read (textureLoad) to the chain's value: rgb light, a AO.
fn chain_value(texel: vec4<f32>) -> vec4<f32> {
    return texel;
}

// A chain value (rgb light, a AO) to the texel textureStore writes.
fn chain_texel(value: vec4<f32>) -> vec4<f32> {
    return value;
}

// The AO of the 2×2 texels around `corner` (a shared texel corner, in uv) of `layer`, in
// textureGather's order: (0, 1), (1, 1), (1, 0), (0, 0) as x, y, z, w.
fn chain_gather_ao(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>, layer: i32) -> vec4<f32> {
    return textureGather(3, t, s, corner, layer);
}
