// The stereo reuse in the denoise's vertical (last) dispatch, shared by the tile denoise
// and the bilateral blur, whose bindings 0–4 it relies on. With two views the left eye
// is filtered first; then the right eye's dispatch (RIGHT_EYE) takes the left eye's
// filtered value wherever the left eye sees the same surface point (common.wgsl
// `left_eye_value`) and filters only the rest (its outer side, disocclusions). The
// right eye's output is then bound as a one-layer view of its layer, beside a sampled
// view of the left eye's layer of the same target.

override RIGHT_EYE: bool = false;
@group(0) @binding(5) var depth_layers: texture_depth_2d_array;
// The output's left-eye layer in the right eye's dispatch (any array texture otherwise).
@group(0) @binding(6) var left_filtered: texture_2d_array<f32>;
// The nearest sampler the left eye's 2×2 blocks are gathered through.
@group(0) @binding(7) var gather: sampler;

// The layer invocation `id` reads (x) and the layer of the bound output it writes (y).
fn denoise_layers(id: vec3<u32>) -> vec2<i32> {
    if (RIGHT_EYE) {
        return vec2<i32>(1, 0);
    }
    return vec2<i32>(i32(id.z));
}

// The left eye's filtered value, where it sees the right eye's point.
struct ReusedValue {
    value: vec4<f32>,
    found: bool,
};

// The left eye's filtered value at the right eye's occlusion pixel `p` (AoGeometry
// `centre`, on a surface), if the left eye sees that point.
fn reused_from_left_eye(p: vec2<i32>, centre: vec4<f32>) -> ReusedValue {
    let right = frame.eyes[1];
    let uv = pixel_uv(full_res_pixel(vec2<u32>(p), ao.scale, frame.size), frame.size);
    let position = view_position_from_distance(uv, centre.w, right.tangents);
    let left = left_eye_value(
        position, right, frame.eyes[0], depth_layers, ao.ao_size, geometry_layers, gather, ao.scale, frame.size, frame.near,
    );
    var reused: ReusedValue;
    reused.found = left.found;
    if (left.found) {
        reused.value = chain_gather_blend(left_filtered, gather, left.corner, 0, left.weights);
    }
    return reused;
}
