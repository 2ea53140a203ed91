// Shared by the occlusion techniques (ssao, hbao, ssdo, fetch): their common bindings
// and the per-pixel set-up every technique starts with.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<storage, read> kernel: array<vec4<f32>>;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var ao_out: ChainTarget;
@group(0) @binding(6) var geometry_out: texture_storage_2d_array<rgba16float, write>;

// Whether the outputs are bound as one-layer views of the receiver's layer (GTAO's
// right-eye dispatch, which reads the left eye's layer of the same targets meanwhile).
override SINGLE_LAYER_OUTPUT: bool = false;

// The layer of the bound outputs that occlusion pixel `id` writes.
fn output_layer(id: vec3<u32>) -> i32 {
    return select(i32(id.z), 0, SINGLE_LAYER_OUTPUT);
}

// The surface an occlusion pixel stands for.
struct Receiver {
    // False outside the target or on the sky (the pixel is then already written).
    valid: bool,
    // False outside the target.
    in_target: bool,
    layer: u32,
    eye: Eye,
    // The full-resolution G-buffer pixel behind this occlusion pixel.
    pixel: vec2<u32>,
    position: vec3<f32>,
    normal: vec3<f32>,
};

// Occlusion pixel `id`'s surface from its depth, without the normal (`with_normal`),
// writing nothing: its pixel, eye and position; invalid outside the target (`in_target`
// false) and on the sky.
fn receiver_point(id: vec3<u32>) -> Receiver {
    var r: Receiver;
    r.valid = false;
    r.in_target = id.x < ao.ao_size.x && id.y < ao.ao_size.y && id.z < frame.layers;
    if (!r.in_target) {
        return r;
    }
    r.layer = id.z;
    r.eye = frame.eyes[id.z];
    r.pixel = full_res_pixel(id.xy, ao.scale, frame.size);
    // A tile the lens hides (visibility.wgsl) is taken as the sky, before any fetch;
    // its hidden pixels in a tile the lens partly shows read as sky in depth already.
    var depth = 0.0;
    if (tile_rate(id.xy, id.z, ao.scale) > 0.0) {
        depth = textureLoad(depth_layers, vec2<i32>(r.pixel), i32(r.layer), 0);
    }
    if (depth <= 0.0) {
        return r;
    }
    r.position = load_view_position(depth, r.pixel, r.eye, frame.size, frame.near);
    r.valid = true;
    return r;
}

// Receiver `point` of `receiver_point` with its normal, where it is valid.
fn with_normal(point: Receiver) -> Receiver {
    var r = point;
    if (r.valid) {
        let stored = textureLoad(normal_layers, vec2<i32>(r.pixel), i32(r.layer), 0).xyz;
        r.normal = repaired_normal(safe_normal(stored, r.position), r.pixel, r.layer, r.eye, r.position);
    }
    return r;
}

// Writes occlusion pixel `id`'s AoGeometry for receiver `r` (with its normal); on the sky
// "unoccluded" as well.
fn store_receiver(id: vec3<u32>, r: Receiver) {
    if (!r.in_target) {
        return;
    }
    if (!r.valid) {
        store_occlusion(id, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        textureStore(geometry_out, vec2<i32>(id.xy), output_layer(id), vec4<f32>(0.0));
        return;
    }
    // Clamped to the half float's range (AoGeometry's format): finite at any distance.
    textureStore(geometry_out, vec2<i32>(id.xy), output_layer(id), vec4<f32>(r.normal, min(-r.position.z, 65504.0)));
}

// Sets up occlusion pixel `id`: reads its depth and normal and writes its AoGeometry; on
// the sky it writes "unoccluded" and returns an invalid receiver.
fn begin_receiver(id: vec3<u32>) -> Receiver {
    let r = with_normal(receiver_point(id));
    store_receiver(id, r);
    return r;
}

// The normal the techniques use. Where the stored (interpolated) normal is grazing, as on
// silhouettes, it is compared with the normal of the depth buffer itself, and replaced by
// it when they disagree by more than 60° (a normal bent into the body made AO 0 there).
// The result always leans at least a little towards the eye: the direction to the eye is
// open (the pixel is seen), so no technique can find the whole hemisphere blocked.
fn repaired_normal(stored: vec3<f32>, pixel: vec2<u32>, layer: u32, eye: Eye, position: vec3<f32>) -> vec3<f32> {
    let view = normalize(-position);
    var n = stored;
    if (dot(n, view) < 0.3) {
        let derived = depth_normal(pixel, layer, eye, position);
        if (dot(n, derived) < 0.5) {
            n = derived;
        }
    }
    let facing = dot(n, view);
    if (facing < 0.05) {
        n = normalize(n + view * (0.05 - facing));
    }
    return n;
}

// The normal of the depth buffer at `pixel`, facing the eye: per axis, the neighbour
// whose distance is closer to the pixel's (the same surface, not across an edge).
fn depth_normal(pixel: vec2<u32>, layer: u32, eye: Eye, position: vec3<f32>) -> vec3<f32> {
    let dx = neighbour_step(pixel, vec2<i32>(1, 0), layer, eye, position);
    let dy = neighbour_step(pixel, vec2<i32>(0, 1), layer, eye, position);
    let n = cross(dx, dy);
    let len2 = dot(n, n);
    if (!(len2 > 1e-30)) {
        return normalize(-position);
    }
    return n * inverseSqrt(len2) * select(-1.0, 1.0, dot(n, -position) >= 0.0);
}

// From `position` to the neighbour along +axis or −axis (whichever lies closer in
// distance), oriented along +axis; 0 when neither is on a surface.
fn neighbour_step(pixel: vec2<u32>, axis: vec2<i32>, layer: u32, eye: Eye, position: vec3<f32>) -> vec3<f32> {
    var best = vec3<f32>(0.0);
    var best_gap = 3.0e38;
    for (var k = -1; k <= 1; k += 2) {
        let q = vec2<i32>(pixel) + axis * k;
        if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(frame.size))) {
            continue;
        }
        let d = textureLoad(depth_layers, q, i32(layer), 0);
        if (!(d > 0.0)) {
            continue;
        }
        let step = (load_view_position(d, vec2<u32>(q), eye, frame.size, frame.near) - position) * f32(k);
        let gap = abs(step.z);
        if (gap < best_gap) {
            best_gap = gap;
            best = step;
        }
    }
    return best;
}

fn store_occlusion(id: vec3<u32>, value: vec4<f32>) {
    textureStore(ao_out, vec2<i32>(id.xy), output_layer(id), chain_texel(value));
}

// Whether the surface found by `probe` occludes a sample for a receiver at `position`
// with normal `n`: the surface lies in front of the sample (by more than `bias`) AND rises
// above the receiver's tangent plane. The second test removes the self-occlusion a flat
// surface gives itself at grazing angles, where one pixel's depth spans far more than the
// bias.
fn occludes(probe: DepthProbe, position: vec3<f32>, n: vec3<f32>, bias: f32) -> bool {
    if (!probe.valid || !(probe.distance < probe.sample_distance - bias)) {
        return false;
    }
    return dot(probe.surface - position, n) > bias + 1e-5 * -position.z;
}

// What the depth buffer holds where a view-space sample point projects: `valid` is false
// off both eyes' images, behind the eye or on the sky. `distance` is the stored surface's
// distance and `sample_distance` the sample's, both along the −z of the eye that saw it
// (`layer`), `pixel` the full-res pixel read there and `surface` the stored surface in
// the receiver's view space.
struct DepthProbe {
    valid: bool,
    layer: u32,
    pixel: vec2<u32>,
    distance: f32,
    sample_distance: f32,
    surface: vec3<f32>,
};

// The full-res pixel where view-space point `s` projects, if on screen and in front of
// the eye (`valid`; `distance` and `surface` are left for the caller's fetch).
fn probe_target(s: vec3<f32>, eye: Eye) -> DepthProbe {
    var probe: DepthProbe;
    probe.valid = false;
    probe.sample_distance = -s.z;
    if (!(-s.z > frame.near * 0.5)) {
        return probe;
    }
    let uv = view_to_uv(s, eye.tangents);
    if (!(all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0)))) {
        return probe;
    }
    probe.pixel = min(vec2<u32>(uv * vec2<f32>(frame.size)), frame.size - vec2<u32>(1u));
    probe.valid = true;
    return probe;
}

// Probes `s` in the receiver's eye; a point off its image is probed in the other eye's
// layer of the same depth buffer (each eye's inner border lies inside the other's view).
fn probe_depth(depth_layers: texture_depth_2d_array, layer: u32, s: vec3<f32>, eye: Eye) -> DepthProbe {
    var probe = probe_target(s, eye);
    probe.layer = layer;
    if (probe.valid) {
        let d = textureLoad(depth_layers, vec2<i32>(probe.pixel), i32(layer), 0);
        probe.valid = d > 0.0;
        probe.distance = frame.near / max(d, 1e-30);
        probe.surface = probed_surface(probe, eye);
        return probe;
    }
    if (frame.layers < 2u) {
        return probe;
    }
    let other_layer = 1u - layer;
    let other = frame.eyes[other_layer];
    let in_other = (eye.other_from_view * vec4<f32>(s, 1.0)).xyz;
    probe = probe_target(in_other, other);
    probe.layer = other_layer;
    if (!probe.valid) {
        return probe;
    }
    let d = textureLoad(depth_layers, vec2<i32>(probe.pixel), i32(other_layer), 0);
    probe.valid = d > 0.0;
    probe.distance = frame.near / max(d, 1e-30);
    probe.surface = (other.other_from_view * vec4<f32>(probed_surface(probe, other), 1.0)).xyz;
    return probe;
}

// The stored surface at the probed pixel's centre, in the view space of the eye that
// was probed. The pixel centre, not the sample's own ray: the depth belongs to the
// centre, and on a surface seen at a grazing angle the sub-pixel difference would lift
// the point above the receiver's tangent plane and make a flat floor occlude itself.
fn probed_surface(probe: DepthProbe, eye: Eye) -> vec3<f32> {
    return view_position_from_distance(pixel_uv(probe.pixel, frame.size), probe.distance, eye.tangents);
}

// The pixel of a `grid`-sized image whose noise value (kernel rotation, slice turn) a
// pixel takes: its own (`own`) in the left eye; in the right eye, that of the left-eye
// pixel that sees its surface point, so both eyes sample the same point alike and
// agree, not just in expectation (the eyes' independent noise made AO differ between
// them). Disparity is smooth, so the right eye still sees every value of a noise tile in
// each tile-sized window away from depth edges.
fn stereo_noise_pixel(own: vec2<u32>, grid: vec2<u32>, layer: u32, eye: Eye, position: vec3<f32>) -> vec2<u32> {
    if (layer == 0u || frame.layers < 2u) {
        return own;
    }
    let in_left = in_other_eye(position, eye, frame.eyes[0], frame.near);
    if (in_left.w == 0.0) {
        return own;
    }
    return vec2<u32>(in_left.xy * vec2<f32>(grid));
}

// The side of this eye's image past which the other eye sees on: +1 right, −1 left, 0
// for a mono view. It is the side the other eye's centre lies on (its x in this view).
fn other_eye_side(eye: Eye) -> f32 {
    let m = eye.other_from_view;
    // The other eye's origin in this view: −Rᵀt for other_from_view = [R | t].
    let t = m[3].xyz;
    let x = -dot(m[0].xyz, t);
    return select(select(0.0, -1.0, x < -1e-6), 1.0, x > 1e-6);
}

// The surface at screen position `q` (full-res pixel coordinates, may lie off the image)
// of layer `layer`, in this eye's view space; w = 0 when none is known. Off the image the
// other eye's layer is asked: the point on this eye's ray through `q` at distance `guess`
// (along −z) is projected into the other eye, and the surface found there is returned
// (screen-space marches: HBAO, GTAO).
fn surface_at(q: vec2<f32>, layer: u32, eye: Eye, guess: f32) -> vec4<f32> {
    let size = vec2<f32>(frame.size);
    if (all(q >= vec2<f32>(0.0)) && all(q < size)) {
        let p = vec2<u32>(q);
        let d = textureLoad(depth_layers, vec2<i32>(p), i32(layer), 0);
        if (!(d > 0.0)) {
            return vec4<f32>(0.0);
        }
        return vec4<f32>(load_view_position(d, p, eye, frame.size, frame.near), 1.0);
    }
    if (frame.layers < 2u) {
        return vec4<f32>(0.0);
    }
    let other_layer = 1u - layer;
    let other = frame.eyes[other_layer];
    let on_ray = view_position_from_distance(q / size, guess, eye.tangents);
    let in_other = in_other_eye(on_ray, eye, other, frame.near);
    if (in_other.w == 0.0) {
        return vec4<f32>(0.0);
    }
    let p = min(vec2<u32>(in_other.xy * size), frame.size - vec2<u32>(1u));
    let d = textureLoad(depth_layers, vec2<i32>(p), i32(other_layer), 0);
    if (!(d > 0.0)) {
        return vec4<f32>(0.0);
    }
    let surface = load_view_position(d, p, other, frame.size, frame.near);
    return vec4<f32>((other.other_from_view * vec4<f32>(surface, 1.0)).xyz, 1.0);
}

// 4×4 interleaved noise: a Bayer order (every 2×2 and 4×4 block holds evenly spread
// values), so the 4×4 denoise window sees each of the 16 values once.
fn bayer4(p: vec2<u32>) -> f32 {
    let x = p.x & 3u;
    let y = p.y & 3u;
    let v = x ^ y;
    let index = ((v & 1u) << 3u) | ((y & 1u) << 2u) | (v & 2u) | ((y & 2u) >> 1u);
    return (f32(index) + 0.5) / 16.0;
}

// Fixed foveation (settings::Foveation): the share of its full sample count occlusion
// pixel `p` spends, read from the visibility map (visibility.wgsl): per tile the rate of
// its point nearest the eye's view axis, from the tangent of that angle (1 within the
// full-rate angle, falling linearly in the tangent to the edge rate). Off, the rate is 1
// everywhere the lens shows.
fn foveation_rate(p: vec2<u32>, layer: u32) -> f32 {
    return tile_rate(p, layer, ao.scale);
}

// `full` samples (or steps, or slices) scaled by `rate` (a foveation rate), as a whole
// count of at least 1: a fractional count rounds up with the probability of its
// fraction, from a 4×4 ordered dither over `cell` (its own order, decorrelated from the
// techniques' rotations), so the denoise averages the rate itself and the map shows no
// step where the count changes. Per occlusion pixel, neighbouring invocations' loops
// differ by at most one iteration (a SIMD group pays the longest).
fn foveated_count(full: u32, rate: f32, cell: vec2<u32>) -> u32 {
    if (rate >= 1.0) {
        return full;
    }
    let dither = fract(bayer4(cell) * 13.0 + 0.40625);
    return clamp(u32(floor(f32(full) * rate + dither)), 1u, full);
}

// A marching technique's slices (directions) and steps per slice under foveation `rate`
// for occlusion pixel `p`: slices go first, down to one, then steps. A pixel's slice
// directions turn with the noise tile, so dropping slices leaves the estimate unbiased
// (the denoise averages the directions of its window); fewer steps along a slice step
// over thin occluders and lighten it. The slice count is dithered per 8×8 block (a
// workgroup), not per pixel: a SIMD group whose pixels marched one or two slices would
// pay two for all of them.
fn foveated_march(slices: u32, steps: u32, rate: f32, p: vec2<u32>) -> vec2<u32> {
    if (rate >= 1.0) {
        return vec2<u32>(slices, steps);
    }
    let kept_slices = foveated_count(slices, max(rate, 1.0 / f32(slices)), p / 8u);
    let step_rate = rate * f32(slices) / f32(kept_slices);
    return vec2<u32>(kept_slices, foveated_count(steps, step_rate, p));
}
