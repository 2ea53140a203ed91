// Shared by every pass: the frame uniforms and the one depth → view-space position
// helper (mirrors `stereo::view_position_from_depth`).

struct Eye {
    // Clip from the scene's anchor frame (geometry is stored relative to an f64 anchor).
    clip_from_anchored: mat4x4<f32>,
    // View from the anchor frame (normals use its rotation).
    view_from_anchored: mat4x4<f32>,
    // World from view, rotation only (environment lookups).
    world_from_view: mat4x4<f32>,
    // tan(left), tan(right), tan(up), tan(down) of the eye's asymmetric frustum.
    tangents: vec4<f32>,
    // The other eye's view from this eye's view (identity for a mono view): occlusion
    // samples that leave this eye's image are looked up in the other eye's layer.
    other_from_view: mat4x4<f32>,
};

struct Frame {
    eyes: array<Eye, 2>,
    size: vec2<u32>,
    layers: u32,
    near: f32,
    has_environment: u32,
    // The environment light as quadratic polynomials in a view-space direction,
    // [a, bx, by, bz, qxx, qyy, qzz, qxy, qxz, qyz] with rgb in xyz, turned into each
    // eye's view space on the CPU: irradiance SH9 (scaled by the environment intensity)
    // of eye 0 and eye 1, then the pre-filtered radiance (SH bands 0 and 1, so its
    // second-order terms are 0) of eye 0 and eye 1 (SSDO); irradiance.wgsl reads them.
    environment_quadratics: array<array<vec4<f32>, 10>, 4>,
};

const PI: f32 = 3.14159265358979;

// Centre of pixel `p` in 0..1 texture coordinates (origin top-left).
fn pixel_uv(p: vec2<u32>, size: vec2<u32>) -> vec2<f32> {
    return (vec2<f32>(p) + vec2<f32>(0.5)) / vec2<f32>(size);
}

// View-space position seen at `uv` with reversed-Z infinite-far depth `depth` (> 0).
// distance = near / depth; x and y follow the frustum tangents, so no inverse matrix
// costs precision.
fn view_position_from_depth(uv: vec2<f32>, depth: f32, tangents: vec4<f32>, near: f32) -> vec3<f32> {
    let distance = near / max(depth, 1e-30);
    let tan_x = mix(tangents.x, tangents.y, uv.x);
    let tan_y = mix(tangents.z, tangents.w, uv.y);
    return vec3<f32>(tan_x * distance, tan_y * distance, -distance);
}

// View-space direction through `uv` (unit length).
fn view_ray(uv: vec2<f32>, tangents: vec4<f32>) -> vec3<f32> {
    return normalize(vec3<f32>(mix(tangents.x, tangents.y, uv.x), mix(tangents.z, tangents.w, uv.y), -1.0));
}

// Replaces NaN and ±Inf by 0 and clamps to the f16 range, so no pass writes a value
// a half-float target cannot hold.
fn finite_or_zero3(v: vec3<f32>) -> vec3<f32> {
    let ok = (v == v) & (abs(v) <= vec3<f32>(3.0e38));
    return clamp(select(vec3<f32>(0.0), v, ok), vec3<f32>(-65504.0), vec3<f32>(65504.0));
}

// How the composite applies the technique's output (`AoParams::technique`; the
// technique table's `CompositeMode`, crates/vrao-ao/src/technique.rs).
const COMPOSITE_UNOCCLUDED: u32 = 0u;
const COMPOSITE_SCALAR_AO: u32 = 1u;
const COMPOSITE_DIRECTIONAL: u32 = 2u;

// Parameters of the occlusion passes (AO technique, blur, upsample, composite).
struct AoParams {
    // Size of the occlusion targets (half the full size, rounded up, with half-res).
    ao_size: vec2<u32>,
    // Full-resolution pixels per occlusion pixel along each axis: 1 or 2.
    scale: u32,
    // SSAO/SSDO samples per pixel.
    samples: u32,
    // HBAO directions and steps per direction (directions × steps ≈ samples).
    directions: u32,
    steps: u32,
    // How the composite applies occlusion: 0 none, 1 scalar AO (SSAO, HBAO),
    // 2 directional (SSDO's gathered irradiance replaces the ambient term).
    technique: u32,
    // 0 tiled 5×5 rotations, 1 Halton/R2 per-pixel rotation.
    noise: u32,
    // World-space radius (metres).
    radius: f32,
    // Occlusion weight in [0, 4].
    strength: f32,
    // Depth bias as a fraction of the radius.
    bias: f32,
    // 1: occluders beyond the radius fade out (range check).
    range_check: u32,
    // SSDO bounce strength (0: no bounce work).
    bounce: f32,
    // Extra kernel rotation this frame (temporal accumulation), radians.
    frame_angle: f32,
    // Bilateral blur radius in occlusion pixels (5 → 11×11 at full resolution).
    blur_radius: u32,
    // Depth-edge width of the blur, as a fraction of the centre's distance.
    blur_plane_sigma: f32,
    // Sample-length scale this frame (temporal range jitter; 1 otherwise).
    range_scale: f32,
    // Pads the struct to 80 bytes, a multiple of 16 (`padding` of AoParamsUniform).
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

// The full-resolution G-buffer pixel that stands for occlusion pixel `p` (its top-left
// full-res pixel, clamped for odd sizes), so every pass at AO resolution agrees on it.
fn full_res_pixel(p: vec2<u32>, scale: u32, full_size: vec2<u32>) -> vec2<u32> {
    return min(p * scale, full_size - vec2<u32>(1u));
}

// Centre of full-resolution pixel `p` in 0..1 texture coordinates.
fn full_res_uv(p: vec2<u32>, full_size: vec2<u32>) -> vec2<f32> {
    return pixel_uv(p, full_size);
}

// Rebuilds a view-space position at an integer full-res pixel of one layer.
fn load_view_position(depth: f32, p: vec2<u32>, eye: Eye, full_size: vec2<u32>, near: f32) -> vec3<f32> {
    return view_position_from_depth(pixel_uv(p, full_size), depth, eye.tangents, near);
}

// View-space position at `uv` of a surface at `distance` along −z (the form AoGeometry
// stores; the same frustum-tangent mapping as `view_position_from_depth`).
fn view_position_from_distance(uv: vec2<f32>, distance: f32, tangents: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(mix(tangents.x, tangents.y, uv.x) * distance, mix(tangents.z, tangents.w, uv.y) * distance, -distance);
}

// Where a view-space point lands: uv (0..1, top-left origin). Uses the frustum tangents,
// the exact inverse of `view_position_from_depth`.
fn view_to_uv(v: vec3<f32>, tangents: vec4<f32>) -> vec2<f32> {
    let inv_distance = 1.0 / max(-v.z, 1e-30);
    let tan_x = v.x * inv_distance;
    let tan_y = v.y * inv_distance;
    return vec2<f32>((tan_x - tangents.x) / (tangents.y - tangents.x), (tan_y - tangents.z) / (tangents.w - tangents.z));
}

// Where view-space point `v` of `eye` lands in the other eye `other`: (uv, distance along
// the other eye's −z, 1), or w = 0 where it lies off that eye's image or not beyond its
// near plane.
fn in_other_eye(v: vec3<f32>, eye: Eye, other: Eye, near: f32) -> vec4<f32> {
    let w = (eye.other_from_view * vec4<f32>(v, 1.0)).xyz;
    let uv = view_to_uv(w, other.tangents);
    let seen = -w.z > near && all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0));
    return vec4<f32>(uv, -w.z, select(0.0, 1.0, seen));
}

// The stereo reuse (GTAO's right-eye march, every technique's denoise): a right-eye
// surface point the left eye also sees takes the left eye's value there. AO within r
// belongs to the surface point, not to the eye, so the eyes then agree by construction.
// Where the value lies: the 2×2 block of the left eye's occlusion pixels a gather at
// `corner` fetches, and the weights of its texels (in gather order, summing to 1) whose
// blend is the value (the chain's `chain_gather_blend`, which this file cannot name:
// not every shader that includes it has an AO chain).
struct LeftEyeValue {
    corner: vec2<f32>,
    weights: vec4<f32>,
    // False where the left eye does not see the point: the right eye computes it.
    found: bool,
};

// Where right-eye view-space point `position` lands in the left eye: its uv, its
// distance along the left eye's −z and the left eye's full-res pixel there. Seen where
// that pixel holds the same surface (its depth within 1 % of the point's distance); not
// off the left image, or where the left eye sees another surface there.
struct LeftEyePoint {
    uv: vec2<f32>,
    distance: f32,
    pixel: vec2<u32>,
    seen: bool,
};

fn left_eye_point(
    position: vec3<f32>,
    right: Eye,
    left: Eye,
    depth: texture_depth_2d_array,
    full_size: vec2<u32>,
    near: f32,
) -> LeftEyePoint {
    var point: LeftEyePoint;
    point.seen = false;
    let in_left = in_other_eye(position, right, left, near);
    if (in_left.w == 0.0) {
        return point;
    }
    point.uv = in_left.xy;
    point.distance = in_left.z;
    point.pixel = min(vec2<u32>(point.uv * vec2<f32>(full_size)), full_size - vec2<u32>(1u));
    point.seen = depth_holds_distance(textureLoad(depth, vec2<i32>(point.pixel), 0, 0), point.distance, near);
    return point;
}

// The second depth layer's lowest mantissa bit (passes/inputs.rs `DEPTH_LAYER_2`): 1 where
// the surface behind the first layer faces the eye. Behind a closed object that surface is
// its own back face, and the span between the layers is inside it; a front face there
// means the first layer is a sheet (a wall of one polygon, an open shell) with the next
// object behind it, and the span is air. One ulp of depth, far below any test's tolerance.
fn second_layer_with_facing(depth: f32, faces_eye: bool) -> f32 {
    return bitcast<f32>((bitcast<u32>(depth) & ~1u) | select(0u, 1u, faces_eye));
}

fn second_layer_faces_eye(depth: f32) -> bool {
    return (bitcast<u32>(depth) & 1u) != 0u;
}

// Whether stored depth `depth` (reversed-Z, infinite far: its distance is near / depth)
// holds a surface within 1 % of `distance`, the stereo reuse's test for the same surface:
// |near / depth − distance| < 0.01 distance, multiplied through by depth (> 0) so that no
// division is left (the right eye's copies make it at every pixel).
fn depth_holds_distance(depth: f32, distance: f32, near: f32) -> bool {
    let there = distance * depth;
    return depth > 0.0 && abs(near - there) < 0.01 * there;
}

// The left eye's value (`left_values`, at occlusion resolution, layer 0; `left_geometry`
// its AoGeometry) at right-eye view-space point `position`, where the left eye sees it
// (`left_eye_point`). Interpolated at the point among the four occlusion pixels around
// it on the same surface (within 5 % in distance): the nearest pixel shifted the eyes'
// AO by up to a pixel against each other, and a neighbour across a depth edge would
// bring another surface's value. Their distances come from one gather through `gather`
// (a nearest sampler clamped to the edge, as a clamped load is); `grid` is the size of
// the occlusion targets.
fn left_eye_value(
    position: vec3<f32>,
    right: Eye,
    left: Eye,
    depth: texture_depth_2d_array,
    grid: vec2<u32>,
    left_geometry: texture_2d_array<f32>,
    gather: sampler,
    scale: u32,
    full_size: vec2<u32>,
    near: f32,
) -> LeftEyeValue {
    var result: LeftEyeValue;
    result.found = false;
    let point = left_eye_point(position, right, left, depth, full_size, near);
    if (!point.seen) {
        return result;
    }
    let f = left_eye_coordinate(point.uv, grid, scale);
    let there = textureGather(3, left_geometry, gather, left_eye_corner(f, grid), 0);
    return left_eye_blend(f, grid, there, point.distance);
}

// Left-eye uv `uv` in occlusion pixels of a `grid`-sized target at 1/`scale` resolution:
// occlusion pixel k stands for the centre of its top-left full-res pixel, so its block
// of 2×2 pixels starts at the floor.
fn left_eye_coordinate(uv: vec2<f32>, grid: vec2<u32>, scale: u32) -> vec2<f32> {
    return uv * vec2<f32>(grid) - 0.5 / f32(scale);
}

// Where a gather fetches the 2×2 block from floor(`f`) (the corner those pixels share):
// in gather order, floor(f) + (0, 1), (1, 1), (1, 0), (0, 0) as x, y, z, w.
fn left_eye_corner(f: vec2<f32>, grid: vec2<u32>) -> vec2<f32> {
    return (floor(f) + vec2<f32>(1.0)) / vec2<f32>(grid);
}

// The blend of the 2×2 block at coordinate `f` (`left_eye_coordinate`; its texels'
// distances `there`, in gather order) for a point `distance` away: bilinear over the
// texels on the same surface (within 5 % in distance); not found where none is.
fn left_eye_blend(f: vec2<f32>, grid: vec2<u32>, there: vec4<f32>, distance: f32) -> LeftEyeValue {
    var result: LeftEyeValue;
    result.found = false;
    let t = f - floor(f);
    let bilinear = vec4<f32>((1.0 - t.x) * t.y, t.x * t.y, t.x * (1.0 - t.y), (1.0 - t.x) * (1.0 - t.y));
    let same = (there > vec4<f32>(0.0)) & (abs(there - vec4<f32>(distance)) < vec4<f32>(0.05 * distance));
    let w = select(vec4<f32>(0.0), bilinear, same);
    let total = dot(w, vec4<f32>(1.0));
    if (total > 1e-6) {
        result.corner = left_eye_corner(f, grid);
        result.weights = w / total;
        result.found = true;
    }
    return result;
}

// The least AO of a surface: 1/256, one ray of the reference tracer's 256 per pixel
// (measure::reference, `vrao bench --rays`) getting out, the smallest visibility above 0
// it reports. A pixel the eye sees has the direction to the eye open, so no estimate
// may call it fully occluded; and 0 would tone-map to pure black wherever no direct
// light falls (an estimate of exactly 0 was GTAO's bug: gtao.wgsl `visible_sectors`).
const AO_FLOOR: f32 = 1.0 / 256.0;

// Clamps to [AO_FLOOR, 1] and maps NaN to 1 (unoccluded): AO never leaves its range.
fn saturate_ao(a: f32) -> f32 {
    return select(1.0, clamp(a, AO_FLOOR, 1.0), a == a);
}

// Equirectangular lookup; the layout matches `scene::Environment::direction`
// (row 0 = +Y, the image centre = −Z, u = 0.75 = +X).
fn environment_radiance(env: texture_2d<f32>, env_sampler: sampler, dir: vec3<f32>) -> vec3<f32> {
    let d = normalize(dir);
    let u = fract(atan2(d.x, -d.z) / (2.0 * PI) + 0.5);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return textureSampleLevel(env, env_sampler, vec2<f32>(u, v), 0.0).rgb;
}

// ---- Occlusion helpers shared by SSAO, HBAO and SSDO ----

// Per-pixel kernel rotation (radians). noise 0: a 5×5 tile repeated over the screen
// (Belonogov 2018), its 25 angles visited in a stride-7 permutation so neighbours differ;
// noise 1: a per-pixel low-discrepancy rotation (the R2 sequence), no visible tile.
fn kernel_rotation(p: vec2<u32>, noise: u32) -> f32 {
    if (noise == 0u) {
        let index = (p.x % 5u) + 5u * (p.y % 5u);
        return 2.0 * PI * f32((index * 7u) % 25u) / 25.0;
    }
    return 2.0 * PI * fract(0.5 + f32(p.x) * 0.7548776662 + f32(p.y) * 0.5698402910);
}

// An orthonormal frame around `n` (columns: tangent, bitangent, normal), turned by
// `angle` about `n`.
fn tangent_frame(n: vec3<f32>, angle: f32) -> mat3x3<f32> {
    let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(n.y) > 0.9);
    let t0 = normalize(cross(helper, n));
    let b0 = cross(n, t0);
    let t = t0 * cos(angle) + b0 * sin(angle);
    return mat3x3<f32>(t, cross(n, t), n);
}

// The unit normal stored at a pixel; a zero or non-finite one becomes the direction to
// the eye, so a broken normal never turns into NaN.
fn safe_normal(stored: vec3<f32>, position: vec3<f32>) -> vec3<f32> {
    let len2 = dot(stored, stored);
    if (len2 > 1e-12 && len2 < 1e12) {
        return stored * inverseSqrt(len2);
    }
    return normalize(-position);
}

// Edge-stopping weight for normals, (n·q)^16 by repeated squaring (no pow): 1 for equal
// normals, 0.5 at about 17°, 0 for perpendicular or opposite ones.
fn normal_agreement(n: vec3<f32>, q: vec3<f32>) -> f32 {
    let c = max(dot(n, q), 0.0);
    let c2 = c * c;
    let c4 = c2 * c2;
    let c8 = c4 * c4;
    return c8 * c8;
}

// The tangent plane of occlusion pixel `p` (AoGeometry `centre`: normal, distance) for
// taps along `axis`: a tap at distance d, k occlusion pixels along the axis, lies
// `plane_offset_of(plane, d, k)` off it, in units of `sigma` × the centre's distance.
// The view ray through an occlusion pixel is (tx, ty, −1), each tangent linear in its
// pixel coordinate, so the offset is (d (e + k f) − d₀ e) with e = n·ray(p) and f = the
// normal's axis component × the tangent's step per pixel: two multiply-adds per tap
// instead of reconstructing its position (the denoise filters are arithmetic-bound on
// lavapipe).
struct TapPlane {
    e: f32,
    f: f32,
    centre_offset: f32,
    scale: f32,
};

fn tap_plane(eye: Eye, p: vec2<u32>, centre: vec4<f32>, axis: vec2<i32>, scale: u32, full_size: vec2<u32>, sigma: f32) -> TapPlane {
    let tangent_step = vec2<f32>(eye.tangents.y - eye.tangents.x, eye.tangents.w - eye.tangents.z)
        * f32(scale) / vec2<f32>(full_size);
    let uv = pixel_uv(full_res_pixel(p, scale, full_size), full_size);
    let ray = vec3<f32>(mix(eye.tangents.x, eye.tangents.y, uv.x), mix(eye.tangents.z, eye.tangents.w, uv.y), -1.0);
    var plane: TapPlane;
    plane.e = dot(ray, centre.xyz);
    plane.f = dot(vec2<f32>(axis) * tangent_step, centre.xy);
    plane.centre_offset = centre.w * plane.e;
    // A sigma near 0 makes offsets huge: taps off the plane get weight 0.
    plane.scale = 1.0 / max(sigma * centre.w, 1e-30);
    return plane;
}

fn plane_offset_of(plane: TapPlane, distance: f32, k: f32) -> f32 {
    return (distance * (plane.e + k * plane.f) - plane.centre_offset) * plane.scale;
}

// One texel of the `Direct` resource (rg32uint, 8 bytes) holds what SSDO's bounce needs
// of a sender pixel: x = its view distance (f32 bits, 0 on the sky; the same value
// occlusion probes compute from depth), y = its outgoing radiance in the shared-exponent
// RGB9E5 form (9-bit mantissas, one 5-bit exponent: 0.1 % of the brightest channel,
// up to MAX_RGB9E5). So the bounce's occluder probe is one fetch that also brings the
// sender's light, instead of a depth fetch plus a sender fetch. At headset sizes the
// texel's size decides how much of the texture stays in cache: the earlier 16-byte
// texel made the bounce relatively costlier at full size than at a quarter of the
// pixels (docs/records/2026-11-29/measurements-in-code.md, direct-texel).
const MAX_RGB9E5: f32 = 65408.0;

fn pack_rgb9e5(c: vec3<f32>) -> u32 {
    let clamped = clamp(c, vec3<f32>(0.0), vec3<f32>(MAX_RGB9E5));
    let brightest = max(clamped.r, max(clamped.g, clamped.b));
    // floor(log2(brightest)) from the float's exponent bits; anything below 2^-16
    // rounds to zero in every channel.
    let exponent_floor = max(i32((bitcast<u32>(brightest) >> 23u) & 0xffu) - 127, -16);
    var exponent = exponent_floor + 16;
    var scale = power_of_two(24 - exponent);
    if (floor(brightest * scale + 0.5) >= 512.0) {
        exponent += 1;
        scale *= 0.5;
    }
    let m = vec3<u32>(floor(clamped * scale + 0.5));
    return m.r | (m.g << 9u) | (m.b << 18u) | (u32(exponent) << 27u);
}

fn unpack_rgb9e5(bits: u32) -> vec3<f32> {
    let m = vec3<u32>(bits, bits >> 9u, bits >> 18u) & vec3<u32>(511u);
    return vec3<f32>(m) * power_of_two(i32(bits >> 27u) - 24);
}

// 2^e for −126 ≤ e ≤ 127, built from the exponent bits: exact, and a few integer
// operations where exp2 is a polynomial on a CPU adapter.
fn power_of_two(e: i32) -> f32 {
    return bitcast<f32>(u32(e + 127) << 23u);
}

fn pack_direct(distance: f32, radiance: vec3<f32>) -> vec4<u32> {
    return vec4<u32>(bitcast<u32>(distance), pack_rgb9e5(radiance), 0u, 0u);
}

fn direct_distance(texel: vec4<u32>) -> f32 {
    return bitcast<f32>(texel.x);
}

fn direct_radiance(texel: vec4<u32>) -> vec3<f32> {
    return unpack_rgb9e5(texel.y);
}
