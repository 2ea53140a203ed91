// The AO chain's texel for the techniques without light (GTAO, SSAO, HBAO): AO alone in
// R16Float, 2 bytes instead of 8. The values stay vec4 (rgb light 0, a AO) inside the
// kernels, so every pass reads and writes both layouts through the same names.
alias ChainTarget = texture_storage_2d_array<r16float, write>;

// A chain texel as read (textureLoad, r = AO) to the chain's value: no light, a AO.
fn chain_value(texel: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, texel.r);
}

// A chain value (a AO) to the texel textureStore writes (r).
fn chain_texel(value: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(value.a, 0.0, 0.0, 1.0);
}

// The texels of the 2×2 block a gather at `corner` (a shared texel corner, in uv) fetches
// from `layer`, weighed by `w` (in gather order) and summed, decoded as `chain_value`
// decodes a texel.
fn chain_gather_blend(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>, layer: i32, w: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, dot(textureGather(0, t, s, corner, layer), w));
}

// The AO of the 2×2 texels around `corner` (a shared texel corner, in uv) of `layer`, in
// textureGather's order: (0, 1), (1, 1), (1, 0), (0, 0) as x, y, z, w.
fn chain_gather_ao(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>, layer: i32) -> vec4<f32> {
    return textureGather(0, t, s, corner, layer);
}
