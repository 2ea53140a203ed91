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

// The texels of the 2×2 block a gather at `corner` (a shared texel corner, in uv) fetches
// from `layer`, weighed by `w` (in gather order) and summed, decoded as `chain_value`
// decodes a texel: one gather per channel.
fn chain_gather_blend(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>, layer: i32, w: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(
        dot(textureGather(0, t, s, corner, layer), w),
        dot(textureGather(1, t, s, corner, layer), w),
        dot(textureGather(2, t, s, corner, layer), w),
        dot(textureGather(3, t, s, corner, layer), w),
    );
}

// The AO of the 2×2 texels around `corner` (a shared texel corner, in uv) of `layer`, in
// textureGather's order: (0, 1), (1, 1), (1, 0), (0, 0) as x, y, z, w.
fn chain_gather_ao(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>, layer: i32) -> vec4<f32> {
    return textureGather(3, t, s, corner, layer);
}
