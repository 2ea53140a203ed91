// The right eye's reuse of the left eye's raw occlusion, shared by the techniques that
// estimate per pixel from the depth buffer (GTAO, SSDO, SSAO, HBAO), after occlusion.wgsl.
// With two views and `stereo_reuse` the left eye runs first; then a right-eye pixel whose
// surface point the left eye sees takes the left eye's raw value there instead of its
// own estimate. The visibility within r is a property of the surface point, not of the
// eye, so the eyes then agree by construction, and the right eye estimates only what the
// left eye cannot see (its outer side, disocclusions). Its outputs are bound as one-layer
// views (occlusion.wgsl `SINGLE_LAYER_OUTPUT`), beside the left eye's layers of AoRaw
// and AoGeometry (common.wgsl `left_eye_value`). First `classify_right_eye` copies every
// pixel it can and lists the pixels left to estimate; then the technique's `main` with
// LISTED_PIXELS runs over the listed pixels alone, 64 to a workgroup, by an indirect
// dispatch: the right eye pays for the pixels the left eye cannot give, not for every
// warp that holds one of them (listing 8×8 tiles of the image instead dispatched every
// tile a silhouette crosses: a quarter of Sibenik's right eye). GTAO (and SSDO on its
// march) can go further (`GtaoSettings::fold_right_eye`): list from the depth alone
// before the left eye marches (`left_eye_value_from_depth`), march the listed pixels in
// the left eye's dispatch and copy after (gtao.wgsl `FOLDED`).
//
// The includer defines `reused_light(value)`: the rgb a copied value carries (its
// gathered light for SSDO, 0 for the AO-only techniques).

override RIGHT_EYE: bool = false;
override LISTED_PIXELS: bool = false;

// AoRaw's and AoGeometry's left-eye layers in the right eye's dispatches (any array
// textures otherwise).
@group(0) @binding(7) var left_occlusion: texture_2d_array<f32>;
@group(0) @binding(8) var left_geometry: texture_2d_array<f32>;

// The right eye's pixels to estimate, listed by `classify_right_eye`, and the indirect
// dispatch's workgroup counts over them (x grows by one per 64 pixels; y = z = 1).
struct RightEyeList {
    groups_x: atomic<u32>,
    groups_y: u32,
    groups_z: u32,
    count: atomic<u32>,
    // Occlusion pixel p packed as p.x | p.y << 16.
    pixels: array<u32>,
};
@group(0) @binding(9) var<storage, read_write> right_list: RightEyeList;
// The nearest sampler the left eye's 2×2 blocks are gathered through.
@group(0) @binding(10) var gather: sampler;

// The right eye's listed occlusion pixel `i`, or none (x = ao_size.x) past the list.
fn listed_right_pixel(i: u32) -> vec3<u32> {
    if (i >= atomicLoad(&right_list.count)) {
        return vec3<u32>(ao.ao_size.x, 0u, 1u);
    }
    let packed = right_list.pixels[i];
    return vec3<u32>(packed & 0xffffu, packed >> 16u, 1u);
}

// Appends right-eye occlusion pixel `id` to the list.
fn list_right_pixel(id: vec3<u32>) {
    let i = atomicAdd(&right_list.count, 1u);
    right_list.pixels[i] = id.x | (id.y << 16u);
    if (i % 64u == 0u) {
        atomicAdd(&right_list.groups_x, 1u);
    }
}

// The right-eye occlusion pixel of invocation `id` (in workgroup `group`, at `local`
// within it): the listed pixel, or none (x = ao_size.x) past the list.
fn right_eye_pixel(id: vec3<u32>, group: vec3<u32>, local: u32) -> vec3<u32> {
    if (LISTED_PIXELS) {
        return listed_right_pixel(group.x * 64u + local);
    }
    return vec3<u32>(id.x, id.y, 1u);
}

// The occlusion pixel of invocation `id` of a technique that runs the whole image in one
// dispatch (SSAO, HBAO): itself, or in the right eye's dispatches the listed pixel.
fn estimated_pixel(id: vec3<u32>, group: vec3<u32>, local: u32) -> vec3<u32> {
    if (RIGHT_EYE) {
        return right_eye_pixel(id, group, local);
    }
    return id;
}

// Right-eye pixel `id`'s value from the left eye where the left eye sees its surface
// point (stored, true), else false; the sky and hidden tiles are stored as open (true).
fn reused_from_left_eye(id: vec3<u32>, r: Receiver) -> bool {
    if (!r.valid) {
        return true;
    }
    let left = left_eye_value(
        r.position, r.eye, frame.eyes[0], depth_layers, ao.ao_size, left_geometry, gather, ao.scale, frame.size, frame.near,
    );
    if (left.found) {
        let value = chain_gather_blend(left_occlusion, gather, left.corner, 0, left.weights);
        store_occlusion(id, vec4<f32>(reused_light(value), value.a));
    }
    return left.found;
}

// The right eye's first dispatch: every pixel the left eye gives a value is stored, and
// every other is listed for the technique's estimate.
@compute @workgroup_size(8, 8, 1)
fn classify_right_eye(@builtin(global_invocation_id) invocation: vec3<u32>) {
    let id = vec3<u32>(invocation.xy, 1u);
    if (reused_from_left_eye(id, begin_receiver(id))) {
        return;
    }
    list_right_pixel(id);
}

// The left eye's distances at the 2×2 block of occlusion pixels from `base` (clamped to
// the target, as the gather's sampler clamps), in gather order, from its depth: what its
// AoGeometry holds once its march has run (0 on the sky and in hidden tiles; rounded to
// AoGeometry's half float). At full resolution one gather; at half, four loads.
fn left_distances_from_depth(base: vec2<f32>) -> vec4<f32> {
    let last = vec2<i32>(ao.ao_size) - vec2<i32>(1);
    let lo = vec2<u32>(clamp(vec2<i32>(base), vec2<i32>(0), last));
    let hi = vec2<u32>(clamp(vec2<i32>(base) + vec2<i32>(1), vec2<i32>(0), last));
    var depth: vec4<f32>;
    if (ao.scale == 1u) {
        depth = textureGather(depth_layers, gather, left_eye_corner(base, ao.ao_size), 0);
    } else {
        let at = vec4<u32>(lo, hi);
        depth = vec4<f32>(
            textureLoad(depth_layers, vec2<i32>(full_res_pixel(at.xw, ao.scale, frame.size)), 0, 0),
            textureLoad(depth_layers, vec2<i32>(full_res_pixel(at.zw, ao.scale, frame.size)), 0, 0),
            textureLoad(depth_layers, vec2<i32>(full_res_pixel(at.zy, ao.scale, frame.size)), 0, 0),
            textureLoad(depth_layers, vec2<i32>(full_res_pixel(at.xy, ao.scale, frame.size)), 0, 0),
        );
    }
    // Hidden tiles read as the sky; the block lies in one tile but at a tile's edge.
    var shown = vec4<bool>(tile_rate(lo, 0u, ao.scale) > 0.0);
    if (any(lo / 8u != hi / 8u)) {
        shown = vec4<bool>(
            tile_rate(vec2<u32>(lo.x, hi.y), 0u, ao.scale) > 0.0,
            tile_rate(hi, 0u, ao.scale) > 0.0,
            tile_rate(vec2<u32>(hi.x, lo.y), 0u, ao.scale) > 0.0,
            shown.w,
        );
    }
    let distance = select(vec4<f32>(0.0), min(vec4<f32>(frame.near) / depth, vec4<f32>(65504.0)), shown & (depth > vec4<f32>(0.0)));
    return vec4<f32>(
        unpack2x16float(pack2x16float(distance.xy)),
        unpack2x16float(pack2x16float(distance.zw)),
    );
}

// `left_eye_value` (common.wgsl) with the left eye's distances from its depth instead of
// its AoGeometry: the same test before the left eye marches (GTAO's folded dispatch lists
// the right eye first) and after it (the copies), so that the two agree pixel for pixel.
fn left_eye_value_from_depth(position: vec3<f32>) -> LeftEyeValue {
    let point = left_eye_point(position, frame.eyes[1], frame.eyes[0], depth_layers, frame.size, frame.near);
    if (!point.seen) {
        var none: LeftEyeValue;
        none.found = false;
        return none;
    }
    let f = left_eye_coordinate(point.uv, ao.ao_size, ao.scale);
    return left_eye_blend(f, ao.ao_size, left_distances_from_depth(floor(f)), point.distance);
}
