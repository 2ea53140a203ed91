// The upsample pass: writes AoFull from half-resolution occlusion (joint_upsample.wgsl),
// one invocation per quad of 2×2 full-res pixels, i.e. per low-res sample. Frames do
// not need it (the composite upsamples inline); the AO engine, debug images and tests do.
// With the stereo reuse (RIGHT_EYE) the right eye runs after the left, its output bound
// as a one-layer view beside the left eye's layer: a dispatch takes the left eye's final
// AO wherever the left eye sees the same point (joint_upsample.wgsl `left_eye_quad`),
// stores it, and lists the quads it does not fully see with the pixels it stored; a
// second, indirect dispatch (FALLBACK) over just those upsamples the right eye's own
// occlusion at the rest. Computing the right eye's own upsample at every quad made this
// pass cost more than with independent eyes (docs/records/2026-11-29/measurements-in-code.md,
// upsample-right-eye).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var geometry_low: texture_2d_array<f32>;
@group(0) @binding(5) var occlusion_low: texture_2d_array<f32>;
@group(0) @binding(6) var occlusion_out: ChainTarget;
// AoFull's left-eye layer in the right eye's dispatch (any array texture otherwise).
@group(0) @binding(7) var left_final: texture_2d_array<f32>;

// The AO in a texel of the left eye's upsampled AO (joint_upsample.wgsl `left_eye_quad`).
fn left_final_ao(texel: vec4<f32>) -> f32 {
    return chain_value(texel).a;
}

// The same for the 2×2 texels a gather at `corner` fetches (layer 0).
fn left_final_gather_ao(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>) -> vec4<f32> {
    return chain_gather_ao(t, s, corner, 0);
}

override RIGHT_EYE: bool = false;
override FALLBACK: bool = false;

// The right-eye quads the left eye does not fully see, and the indirect dispatch's
// workgroup counts over them (x grows by one per 64 quads listed; y = z = 1).
struct FallbackQuads {
    groups_x: atomic<u32>,
    groups_y: u32,
    groups_z: u32,
    count: atomic<u32>,
    // Quad b and the pixels already stored from the left eye (joint_upsample.wgsl `pack_quad`).
    quads: array<u32>,
};
@group(0) @binding(8) var<storage, read_write> fallback: FallbackQuads;
@group(0) @binding(9) var gather: sampler;

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) invocation: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    var id = invocation;
    // The pixels of the quad that this dispatch leaves as they are (bit k for pixel k).
    var keep = 0u;
    if (FALLBACK) {
        let i = group.x * 64u + local;
        if (i >= atomicLoad(&fallback.count)) {
            return;
        }
        let quad = unpack_quad(fallback.quads[i]);
        id = vec3<u32>(quad.xy, 0u);
        keep = quad.z;
    } else if (id.x * 2u >= frame.size.x || id.y * 2u >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    // The layer read, and the layer of the bound output written.
    let layer = select(id.z, 1u, RIGHT_EYE);
    let out_layer = select(id.z, 0u, RIGHT_EYE);
    let eye = frame.eyes[layer];
    if (tile_rate(id.xy, layer, 2u) == 0.0) {
        // A 16×16 tile the lens hides (visibility.wgsl): unoccluded, as the sky, unfetched.
        for (var k = 0u; k < 4u; k++) {
            let pixel = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
            if (all(pixel < frame.size)) {
                textureStore(occlusion_out, vec2<i32>(pixel), i32(out_layer), chain_texel(vec4<f32>(0.0, 0.0, 0.0, 1.0)));
            }
        }
        return;
    }
    var quad: array<UpsamplePixel, 4>;
    var values: array<vec4<f32>, 4>;
    if (RIGHT_EYE && !FALLBACK) {
        quad = quad_positions(depth_layers, gather, id.xy, layer, eye);
        let left = left_eye_quad(depth_layers, left_final, gather, quad);
        values = left.values;
        if (!all(left.found)) {
            let i = atomicAdd(&fallback.count, 1u);
            fallback.quads[i] = pack_quad(id.xy, left.found);
            if (i % 64u == 0u) {
                atomicAdd(&fallback.groups_x, 1u);
            }
            keep = quad_bits(!left.found);
        }
    } else {
        // Either eye's own upsample (the right eye's FALLBACK: of the pixels the left eye
        // does not see).
        quad = quad_pixels(depth_layers, normal_layers, id.xy, layer, eye);
        values = upsample_quad(geometry_low, occlusion_low, quad, vec2<i32>(id.xy), layer, eye.tangents, true);
    }
    store(quad[0], out_layer, values[0], (keep & 1u) == 0u);
    store(quad[1], out_layer, values[1], (keep & 2u) == 0u);
    store(quad[2], out_layer, values[2], (keep & 4u) == 0u);
    store(quad[3], out_layer, values[3], (keep & 8u) == 0u);
}

// Stores a quad pixel's value (unoccluded on the sky) if `write`, unless it lies past an
// odd edge.
fn store(px: UpsamplePixel, layer: u32, value: vec4<f32>, write: bool) {
    if (write && all(px.pixel < frame.size)) {
        let sky = px.depth <= 0.0;
        textureStore(occlusion_out, vec2<i32>(px.pixel), i32(layer), chain_texel(select(value, vec4<f32>(0.0, 0.0, 0.0, 1.0), sky)));
    }
}
