// The default denoise: an edge-aware 4×4 box at occlusion resolution, matched to GTAO's
// 4×4 interleaved noise tile (each window holds every one of its 16 patterns once), in
// one pass. One invocation filters a 2×2 quad of pixels: their four windows (offsets −2
// to +1 about each pixel) together cover 5×5 texels, so each texel is fetched once per
// quad, 6.25 fetches per pixel instead of the 11×11 separable blur's 22.
//
// A tap counts for a pixel by how far it lies off the pixel's tangent plane, relative
// to the pixel's distance (a tent, no exp): depth edges stay sharp. Where a pixel's
// neighbours are almost all rejected (a lone pixel, a thin feature), the plain mean of
// its window is blended in, so no isolated extreme value survives untouched.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var geometry_layers: texture_2d_array<f32>;
@group(0) @binding(3) var occlusion_in: texture_2d_array<f32>;
@group(0) @binding(4) var occlusion_out: texture_storage_2d_array<rgba16float, write>;

// One output pixel of the quad: its plane and its running sums.
struct Filtered {
    valid: bool,
    pixel: vec2<i32>,
    // Off-plane distance of a tap at distance d and offset k: (d (e + k·f) − d₀ e) × scale.
    e: f32,
    f: vec2<f32>,
    centre_offset: f32,
    scale: f32,
    sum: vec4<f32>,
    total: f32,
    plain_sum: vec4<f32>,
    plain_count: f32,
};

fn filtered_pixel(p: vec2<i32>, layer: i32, eye: Eye) -> Filtered {
    var out: Filtered;
    out.pixel = p;
    out.valid = all(p < vec2<i32>(ao.ao_size));
    if (!out.valid) {
        return out;
    }
    let centre = textureLoad(geometry_layers, p, layer, 0);
    out.valid = centre.w > 0.0;
    // The view ray through the pixel and its step per occlusion pixel (low-res q stands
    // for full-res scale·q), as in bilateral.wgsl.
    let uv = pixel_uv(full_res_pixel(vec2<u32>(p), ao.scale, frame.size), frame.size);
    let ray = vec3<f32>(mix(eye.tangents.x, eye.tangents.y, uv.x), mix(eye.tangents.z, eye.tangents.w, uv.y), -1.0);
    let tangent_step = vec2<f32>(eye.tangents.y - eye.tangents.x, eye.tangents.w - eye.tangents.z)
        * f32(ao.scale) / vec2<f32>(frame.size);
    out.e = dot(ray, centre.xyz);
    out.f = tangent_step * centre.xy;
    out.centre_offset = centre.w * out.e;
    out.scale = 1.0 / max(ao.blur_plane_sigma * centre.w, 1e-30);
    return out;
}

// Adds tap `value` at distance `distance`, `offset` texels from the pixel, if the tap
// lies in the pixel's window (offsets −2..1 on each axis).
fn add_tap(px: ptr<function, Filtered>, offset: vec2<i32>, distance: f32, value: vec4<f32>) {
    if (any(offset < vec2<i32>(-2)) || any(offset > vec2<i32>(1))) {
        return;
    }
    (*px).plain_sum += value;
    (*px).plain_count += 1.0;
    let k = vec2<f32>(offset);
    let plane = (distance * ((*px).e + dot(k, (*px).f)) - (*px).centre_offset) * (*px).scale;
    let w = max(1.0 - abs(plane), 0.0);
    if (w > 0.0) {
        (*px).sum += value * w;
        (*px).total += w;
    }
}

fn finish(px: Filtered, layer: i32) {
    if (!all(px.pixel < vec2<i32>(ao.ao_size))) {
        return;
    }
    if (!px.valid) {
        // Sky: passed through.
        textureStore(occlusion_out, px.pixel, layer, textureLoad(occlusion_in, px.pixel, layer, 0));
        return;
    }
    // The centre alone weighs 1; below 2 the window's plain mean makes up the rest.
    let prior = max(2.0 - px.total, 0.0);
    let plain = px.plain_sum / max(px.plain_count, 1.0);
    let result = (px.sum + plain * prior) / max(px.total + prior, 1e-20);
    textureStore(occlusion_out, px.pixel, layer, vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a)));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let origin = vec2<i32>(id.xy) * 2;
    if (any(origin >= vec2<i32>(ao.ao_size)) || id.z >= frame.layers) {
        return;
    }
    let layer = i32(id.z);
    let eye = frame.eyes[id.z];
    // The quad's pixels, written out (lavapipe keeps loop-indexed arrays in memory).
    var p00 = filtered_pixel(origin, layer, eye);
    var p10 = filtered_pixel(origin + vec2<i32>(1, 0), layer, eye);
    var p01 = filtered_pixel(origin + vec2<i32>(0, 1), layer, eye);
    var p11 = filtered_pixel(origin + vec2<i32>(1, 1), layer, eye);
    for (var dy = -2; dy <= 2; dy++) {
        for (var dx = -2; dx <= 2; dx++) {
            let q = origin + vec2<i32>(dx, dy);
            if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(ao.ao_size))) {
                continue;
            }
            let distance = textureLoad(geometry_layers, q, layer, 0).w;
            if (!(distance > 0.0)) {
                continue;
            }
            let value = textureLoad(occlusion_in, q, layer, 0);
            let d = vec2<i32>(dx, dy);
            add_tap(&p00, d, distance, value);
            add_tap(&p10, d - vec2<i32>(1, 0), distance, value);
            add_tap(&p01, d - vec2<i32>(0, 1), distance, value);
            add_tap(&p11, d - vec2<i32>(1, 1), distance, value);
        }
    }
    finish(p00, layer);
    finish(p10, layer);
    finish(p01, layer);
    finish(p11, layer);
}
