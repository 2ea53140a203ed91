// Joint bilateral upsampling (Kopf et al. 2007; the Czech SSDO thesis: 3×3, not separated) of
// half-resolution occlusion, shared by the upsample pass (which writes AoFull for debug
// images and tests) and the composite (which upsamples inline, so a frame needs no
// full-resolution occlusion target). One invocation upsamples the quad of 2×2 full-res
// pixels 2b + {0, 1}² of low-res sample b: all four have the same 2×2 (and 3×3)
// low-res neighbourhood, so each sample is fetched once per quad instead of once per
// pixel. On lavapipe the fetches, not the weights, are what upsampling costs
// (docs/records/2026-11-29/measurements-in-code.md, upsample-per-quad). The quad's four pixels live in
// arrays indexed only by constants (calls written out four times, never a loop over
// them): lavapipe keeps an array indexed by a loop counter in memory, which made the
// per-quad composite slower than a per-pixel one (docs/records/2026-11-29/measurements-in-code.md,
// upsample-loop-arrays). Each low-res neighbour is
// weighted by its distance to the pixel and by how well its geometry (normal and
// distance in AoGeometry, from the full-res pixel it was computed at) matches:
// tangent-plane distance and normal. Odd sizes work because low-res pixel q stands for
// full-res pixel min(2q, size − 1). The low-res size is the texture's own, so
// any half-resolution target (occlusion, the RSM bounce) upsamples with it.

const PLANE_SIGMA: f32 = 0.02;
// Below this plane-and-normal agreement of any of the 2×2 nearest samples, the pixel is
// treated as an edge and gets the full 3×3.
const EDGE_AGREEMENT: f32 = 0.5;

// A low-res sample as the pixels of a quad see it.
struct LowResSample {
    // View-space position and normal where it was computed (`full_res_pixel`).
    position: vec3<f32>,
    normal: vec3<f32>,
    // 1 on the target and off the sky, else 0 (its weight vanishes).
    valid: f32,
    value: vec4<f32>,
};

// A texel of `value_low` as a value: decoded as the AO chain's (`chain_value`) when
// `chain` says it is one (the occlusion), as it is otherwise (the RSM's light).
fn low_res_value(texel: vec4<f32>, chain: bool) -> vec4<f32> {
    return select(texel, chain_value(texel), chain);
}

fn low_res_sample(
    geometry_low: texture_2d_array<f32>,
    value_low: texture_2d_array<f32>,
    q: vec2<i32>,
    layer: u32,
    tangents: vec4<f32>,
    chain: bool,
) -> LowResSample {
    let last = vec2<i32>(textureDimensions(value_low)) - 1;
    let clamped = clamp(q, vec2<i32>(0), last);
    let geometry = textureLoad(geometry_low, clamped, i32(layer), 0);
    let fq = full_res_pixel(vec2<u32>(clamped), 2u, frame.size);
    var s: LowResSample;
    s.valid = select(0.0, 1.0, all(q == clamped) && geometry.w > 0.0);
    s.position = view_position_from_distance(pixel_uv(fq, frame.size), geometry.w, tangents);
    s.normal = geometry.xyz;
    s.value = low_res_value(textureLoad(value_low, clamped, i32(layer), 0), chain);
    return s;
}

// One full-res pixel of a quad and its running joint bilateral sum.
struct UpsamplePixel {
    // Where it would be stored; past an odd edge it lies outside the target and its
    // callers skip the store.
    pixel: vec2<u32>,
    // Where its G-buffer values come from: `pixel` clamped into the target.
    texel: vec2<u32>,
    // Its stored depth (0 on the sky) and normal, as the G-buffer holds them.
    depth: f32,
    stored_normal: vec3<f32>,
    position: vec3<f32>,
    n: vec3<f32>,
    // n·position × plane_scale: a sample's plane distance is then one dot and a subtract.
    plane_offset: f32,
    plane_scale: f32,
    sum: vec4<f32>,
    total: f32,
    // The same sum over the samples on any surface, by distance only: the fallback when
    // the geometry rejects them all (a pixel whose normal points into the body).
    surface_sum: vec4<f32>,
    surface_total: f32,
    // The least geometric agreement of the samples so far (edge test).
    agree: f32,
};

// Pixel `k` (0..3) of the quad of low-res sample `b`, with its G-buffer depth and
// normal, its view position and normal, and an empty sum. A sky pixel (depth 0) gets a
// far-away position; its result is not used.
fn upsample_pixel(
    depth_layers: texture_depth_2d_array,
    normal_layers: texture_2d_array<f32>,
    b: vec2<u32>,
    k: u32,
    layer: u32,
    eye: Eye,
) -> UpsamplePixel {
    var px: UpsamplePixel;
    px.pixel = b * 2u + vec2<u32>(k & 1u, k >> 1u);
    px.texel = min(px.pixel, frame.size - vec2<u32>(1u));
    px.depth = textureLoad(depth_layers, vec2<i32>(px.texel), i32(layer), 0);
    px.stored_normal = textureLoad(normal_layers, vec2<i32>(px.texel), i32(layer), 0).xyz;
    px.position = load_view_position(max(px.depth, 1e-30), px.texel, eye, frame.size, frame.near);
    px.n = safe_normal(px.stored_normal, px.position);
    px.plane_scale = 1.0 / (PLANE_SIGMA * -px.position.z);
    px.plane_offset = dot(px.n, px.position) * px.plane_scale;
    px.sum = vec4<f32>(0.0);
    px.total = 0.0;
    px.surface_sum = vec4<f32>(0.0);
    px.surface_total = 0.0;
    px.agree = 1.0;
    return px;
}

// Pixel `k` of the quad of low-res sample `b` at stored depth `depth`, with its view
// position alone: what the right eye's reuse of the left eye's result reads
// (`left_eye_quad`), which has no use for the normal.
fn quad_position(depth: f32, b: vec2<u32>, k: u32, eye: Eye) -> UpsamplePixel {
    var px: UpsamplePixel;
    px.pixel = b * 2u + vec2<u32>(k & 1u, k >> 1u);
    px.texel = min(px.pixel, frame.size - vec2<u32>(1u));
    px.depth = depth;
    px.position = load_view_position(max(px.depth, 1e-30), px.texel, eye, frame.size, frame.near);
    return px;
}

// The uv of the corner that texels `p` and `p` + (1, 1) share: a gather there fetches
// the 2×2 block from `p` (its coordinate lies half a texel inside each, far from any
// rounding edge); clamped to the edge past the last row or column.
fn gather_corner(p: vec2<u32>) -> vec2<f32> {
    return vec2<f32>(p + vec2<u32>(1u)) / vec2<f32>(frame.size);
}

// The four pixels of the quad of low-res sample `b`, as `quad_position` gives them, their
// depths from one gather instead of four loads (clamped at an odd edge, as `texel` is).
fn quad_positions(depth_layers: texture_depth_2d_array, gather: sampler, b: vec2<u32>, layer: u32, eye: Eye) -> array<UpsamplePixel, 4> {
    let depth = textureGather(depth_layers, gather, gather_corner(b * 2u), i32(layer));
    return array<UpsamplePixel, 4>(
        quad_position(depth.w, b, 0u, eye),
        quad_position(depth.z, b, 1u, eye),
        quad_position(depth.x, b, 2u, eye),
        quad_position(depth.y, b, 3u, eye),
    );
}

// The four pixels of the quad of low-res sample `b`.
fn quad_pixels(
    depth_layers: texture_depth_2d_array,
    normal_layers: texture_2d_array<f32>,
    b: vec2<u32>,
    layer: u32,
    eye: Eye,
) -> array<UpsamplePixel, 4> {
    return array<UpsamplePixel, 4>(
        upsample_pixel(depth_layers, normal_layers, b, 0u, layer, eye),
        upsample_pixel(depth_layers, normal_layers, b, 1u, layer, eye),
        upsample_pixel(depth_layers, normal_layers, b, 2u, layer, eye),
        upsample_pixel(depth_layers, normal_layers, b, 3u, layer, eye),
    );
}

// Weighs sample `s` into pixel `px` if `take`: its distance to the pixel's tangent plane
// and its normal agreement (the geometric part), times `spatial`, 1 / (1 + the squared
// full-res pixel distance between them) (`spatial_weight`).
fn add_sample(pixel: UpsamplePixel, s: LowResSample, spatial: f32, take: bool) -> UpsamplePixel {
    var px = pixel;
    let plane = dot(s.position, px.n) * px.plane_scale - px.plane_offset;
    let agreement = s.valid * exp(-plane * plane) * normal_agreement(px.n, s.normal);
    let w = agreement * spatial;
    let finite = w == w;
    let ok = finite && take;
    px.sum += s.value * select(0.0, w, ok);
    px.total += select(0.0, w, ok);
    let on_surface = select(0.0, s.valid * spatial, take);
    px.surface_sum += s.value * on_surface;
    px.surface_total += on_surface;
    px.agree = min(px.agree, select(0.0, agreement, finite));
    return px;
}

// 1 / (1 + d²) for the full-res distance d between pixel k of the quad of b and low-res
// sample b + `offset`, computed at full-res pixel 2(b + offset) (a sample clamped at the
// border is invalid and gets weight 0 anyway).
fn spatial_weight(offset: vec2<i32>, k: i32) -> f32 {
    let d = vec2<f32>(2 * offset - vec2<i32>(k & 1, k >> 1u));
    return 1.0 / (1.0 + dot(d, d));
}

// Sample `s` at low-res offset `offset` from b, weighed into each pixel of the quad
// that `take` selects.
fn add_to_quad(quad: array<UpsamplePixel, 4>, s: LowResSample, offset: vec2<i32>, take: vec4<bool>) -> array<UpsamplePixel, 4> {
    return array<UpsamplePixel, 4>(
        add_sample(quad[0], s, spatial_weight(offset, 0), take.x),
        add_sample(quad[1], s, spatial_weight(offset, 1), take.y),
        add_sample(quad[2], s, spatial_weight(offset, 2), take.z),
        add_sample(quad[3], s, spatial_weight(offset, 3), take.w),
    );
}

// The pixel's upsampled value. When the geometry rejected every sample, the samples on
// any surface by distance alone (never one value that happens to be nearest: on a
// silhouette that is often the sky's, rgb 0, which made SSDO's ambient black); with
// none on a surface either, `nearest` (low-res sample b's).
fn upsampled(px: UpsamplePixel, nearest: vec4<f32>) -> vec4<f32> {
    var result = nearest;
    if (px.total > 1e-20) {
        result = px.sum / px.total;
    } else if (px.surface_total > 1e-20) {
        result = px.surface_sum / px.surface_total;
    }
    return vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
}

// The upsampled values of the four pixels of `quad`, the quad of low-res sample `b`:
// the 2×2 samples b + {0, 1}² first; where any pixel disagrees with them (an edge), the
// rest of the 3×3 around b for the pixels that do. `chain`: `value_low` is a texture of
// the AO chain (`low_res_value`).
fn upsample_quad(
    geometry_low: texture_2d_array<f32>,
    value_low: texture_2d_array<f32>,
    quad: array<UpsamplePixel, 4>,
    b: vec2<i32>,
    layer: u32,
    tangents: vec4<f32>,
    chain: bool,
) -> array<vec4<f32>, 4> {
    if (tile_rate(vec2<u32>(b), layer, 2u) <= THIN_BELOW_RATE) {
        return foveated_quad(value_low, b, layer, chain);
    }
    let every = vec4<bool>(true);
    let nearest = low_res_sample(geometry_low, value_low, b, layer, tangents, chain);
    var pixels = add_to_quad(quad, nearest, vec2<i32>(0, 0), every);
    pixels = add_to_quad(pixels, low_res_sample(geometry_low, value_low, b + vec2<i32>(1, 0), layer, tangents, chain), vec2<i32>(1, 0), every);
    pixels = add_to_quad(pixels, low_res_sample(geometry_low, value_low, b + vec2<i32>(0, 1), layer, tangents, chain), vec2<i32>(0, 1), every);
    pixels = add_to_quad(pixels, low_res_sample(geometry_low, value_low, b + vec2<i32>(1, 1), layer, tangents, chain), vec2<i32>(1, 1), every);
    // Which pixels take the 3×3, decided before any of it is added.
    let edge = vec4<f32>(pixels[0].agree, pixels[1].agree, pixels[2].agree, pixels[3].agree) < vec4<f32>(EDGE_AGREEMENT);
    if (any(edge)) {
        for (var i = 0; i < 5; i++) {
            // (-1,-1) (0,-1) (1,-1) (-1,0) (-1,1): the rest of the 3×3.
            let offset = select(vec2<i32>(-1, i - 2), vec2<i32>(i - 1, -1), i < 3);
            let s = low_res_sample(geometry_low, value_low, b + offset, layer, tangents, chain);
            pixels = add_to_quad(pixels, s, offset, edge);
        }
    }
    return array<vec4<f32>, 4>(
        upsampled(pixels[0], nearest.value),
        upsampled(pixels[1], nearest.value),
        upsampled(pixels[2], nearest.value),
        upsampled(pixels[3], nearest.value),
    );
}

// Foveated towards the image's edge (visibility.wgsl, THIN_BELOW_RATE), where the
// technique marches fewer slices: the quad's values from the 2×2 low-res samples by
// distance alone, four value fetches and no geometry, instead of four to nine samples of
// both weighed by the surface. Smooth as the joint weights are, so the eyes still agree,
// but an edge there may take a little of the other side's occlusion.
fn foveated_quad(value_low: texture_2d_array<f32>, b: vec2<i32>, layer: u32, chain: bool) -> array<vec4<f32>, 4> {
    let limit = vec2<i32>(textureDimensions(value_low)) - vec2<i32>(1);
    let v00 = low_res_value(textureLoad(value_low, min(b, limit), i32(layer), 0), chain);
    let v10 = low_res_value(textureLoad(value_low, min(b + vec2<i32>(1, 0), limit), i32(layer), 0), chain);
    let v01 = low_res_value(textureLoad(value_low, min(b + vec2<i32>(0, 1), limit), i32(layer), 0), chain);
    let v11 = low_res_value(textureLoad(value_low, min(b + vec2<i32>(1, 1), limit), i32(layer), 0), chain);
    return array<vec4<f32>, 4>(
        distance_weighted(v00, v10, v01, v11, 0),
        distance_weighted(v00, v10, v01, v11, 1),
        distance_weighted(v00, v10, v01, v11, 2),
        distance_weighted(v00, v10, v01, v11, 3),
    );
}

// Quad pixel `k`'s value from the 2×2 low-res samples by `spatial_weight` alone.
fn distance_weighted(v00: vec4<f32>, v10: vec4<f32>, v01: vec4<f32>, v11: vec4<f32>, k: i32) -> vec4<f32> {
    let w = vec4<f32>(
        spatial_weight(vec2<i32>(0, 0), k),
        spatial_weight(vec2<i32>(1, 0), k),
        spatial_weight(vec2<i32>(0, 1), k),
        spatial_weight(vec2<i32>(1, 1), k),
    );
    let v = (v00 * w.x + v10 * w.y + v01 * w.z + v11 * w.w) / (w.x + w.y + w.z + w.w);
    return vec4<f32>(finite_or_zero3(v.rgb), saturate_ao(v.a));
}

// The stereo reuse of the upsampled occlusion (half resolution, AO-only techniques): a
// right-eye pixel whose surface point the left eye sees (common.wgsl `left_eye_point`)
// takes the left eye's upsampled AO at the left pixel the point lands on (`left_final`,
// full resolution, its layer 0, AO in .a). The occlusion is then interpolated once, in
// the left eye, instead of once per eye from two low-res grids that sample different
// surface points (that double interpolation left the eyes disagreeing at half
// resolution although the denoise already reuses the left eye).
// The nearest left pixel, not a bilinear blend: far fewer fetches than its own upsample's
// (three gathers a quad where it lands on a 2×2 block, `quad_in_left_eye`), and the
// shift is under a full-res pixel of a field the denoise smoothed.
// The AO in a texel of `left_final` comes from the includer's `left_final_ao` (the
// upsampling's is a chain texture, the composite's its HDR colour with AO in alpha), in
// a gather's four texels from its `left_final_gather_ao`.

// Where the four pixels of a right-eye quad land in the left eye, and which of them it
// sees: from depth alone (the left eye's AO is fetched after, where it is used).
struct QuadInLeftEye {
    // The left pixel that pixel k lands on (meaningful where it is seen, off the sky).
    pixels: array<vec2<u32>, 4>,
    // Seen by the left eye (common.wgsl `left_eye_point`'s test), or on the sky, which
    // takes nothing from it.
    seen: vec4<bool>,
    sky: vec4<bool>,
    // All four on a surface and landing on the 2×2 block from pixels[0].
    block: bool,
};

// Whether the left eye sees a right-eye point (from `in_other_eye`: uv, distance, on its
// image) where it holds stored depth `there`.
fn left_eye_holds(in_left: vec4<f32>, there: f32) -> bool {
    return in_left.w > 0.0 && depth_holds_distance(there, in_left.z, frame.near);
}

// `left_eye_holds` with the left depth loaded at the pixel, for a point off any block.
fn left_eye_holds_alone(in_left: vec4<f32>, pixel: vec2<u32>, depth_layers: texture_depth_2d_array, sky: bool) -> bool {
    if (sky) {
        return true;
    }
    if (in_left.w == 0.0) {
        return false;
    }
    return left_eye_holds(in_left, textureLoad(depth_layers, vec2<i32>(pixel), 0, 0));
}

// Where a smooth surface faces both eyes, the quad's four pixels land on a 2×2 block of
// left pixels: then their left depths come from one gather (and `left_eye_quad`'s AO
// from another). Elsewhere (an edge, the sky, the left image's border) each pixel's
// depth is loaded alone.
fn quad_in_left_eye(depth_layers: texture_depth_2d_array, gather: sampler, quad: array<UpsamplePixel, 4>) -> QuadInLeftEye {
    let right = frame.eyes[1];
    let left = frame.eyes[0];
    let in0 = in_other_eye(quad[0].position, right, left, frame.near);
    let in1 = in_other_eye(quad[1].position, right, left, frame.near);
    let in2 = in_other_eye(quad[2].position, right, left, frame.near);
    let in3 = in_other_eye(quad[3].position, right, left, frame.near);
    let size = vec2<f32>(frame.size);
    let last = frame.size - vec2<u32>(1u);
    var q: QuadInLeftEye;
    q.pixels = array<vec2<u32>, 4>(
        min(vec2<u32>(in0.xy * size), last),
        min(vec2<u32>(in1.xy * size), last),
        min(vec2<u32>(in2.xy * size), last),
        min(vec2<u32>(in3.xy * size), last),
    );
    q.sky = !(vec4<f32>(quad[0].depth, quad[1].depth, quad[2].depth, quad[3].depth) > vec4<f32>(0.0));
    let p0 = q.pixels[0];
    q.block = all(vec4<f32>(in0.w, in1.w, in2.w, in3.w) > vec4<f32>(0.0))
        && !any(q.sky)
        && all(q.pixels[1] == p0 + vec2<u32>(1u, 0u))
        && all(q.pixels[2] == p0 + vec2<u32>(0u, 1u))
        && all(q.pixels[3] == p0 + vec2<u32>(1u, 1u))
        && all(p0 + vec2<u32>(1u) < frame.size);
    if (q.block) {
        // Gather order: (0, 1), (1, 1), (1, 0), (0, 0) as x, y, z, w.
        let there = textureGather(depth_layers, gather, gather_corner(p0), 0);
        q.seen = vec4<bool>(
            left_eye_holds(in0, there.w),
            left_eye_holds(in1, there.z),
            left_eye_holds(in2, there.x),
            left_eye_holds(in3, there.y),
        );
    } else {
        q.seen = vec4<bool>(
            left_eye_holds_alone(in0, q.pixels[0], depth_layers, q.sky.x),
            left_eye_holds_alone(in1, q.pixels[1], depth_layers, q.sky.y),
            left_eye_holds_alone(in2, q.pixels[2], depth_layers, q.sky.z),
            left_eye_holds_alone(in3, q.pixels[3], depth_layers, q.sky.w),
        );
    }
    return q;
}

// The left eye's final AO at the four pixels of a right-eye quad, and which of them the
// left eye sees.
struct LeftEyeQuad {
    values: array<vec4<f32>, 4>,
    found: vec4<bool>,
};

// The left eye's AO at `pixel` where `take` (a seen point off the sky), else 1 (the
// sky's; a point not seen takes nothing).
fn left_final_at(left_final: texture_2d_array<f32>, pixel: vec2<u32>, take: bool) -> f32 {
    if (take) {
        return left_final_ao(textureLoad(left_final, vec2<i32>(pixel), 0, 0));
    }
    return 1.0;
}

fn left_eye_quad(depth_layers: texture_depth_2d_array, left_final: texture_2d_array<f32>, gather: sampler, quad: array<UpsamplePixel, 4>) -> LeftEyeQuad {
    let q = quad_in_left_eye(depth_layers, gather, quad);
    var ao: vec4<f32>;
    if (q.block) {
        ao = left_final_gather_ao(left_final, gather, gather_corner(q.pixels[0])).wzxy;
    } else {
        let take = q.seen & !q.sky;
        ao = vec4<f32>(
            left_final_at(left_final, q.pixels[0], take.x),
            left_final_at(left_final, q.pixels[1], take.y),
            left_final_at(left_final, q.pixels[2], take.z),
            left_final_at(left_final, q.pixels[3], take.w),
        );
    }
    let none = vec3<f32>(0.0);
    var result: LeftEyeQuad;
    result.values = array<vec4<f32>, 4>(vec4<f32>(none, ao.x), vec4<f32>(none, ao.y), vec4<f32>(none, ao.z), vec4<f32>(none, ao.w));
    result.found = q.seen;
    return result;
}

// A right-eye quad that falls back, as its list holds it: b.x and b.y in 14 bits each (a
// side of up to 32768 pixels, beyond any device's texture limit), then bit k set where
// pixel k was already stored from the left eye (`found`).
fn pack_quad(b: vec2<u32>, found: vec4<bool>) -> u32 {
    return b.x | (b.y << 14u) | (quad_bits(found) << 28u);
}

// The quad `pack_quad` packed, and (z) the bits of the pixels already stored.
fn unpack_quad(packed: u32) -> vec3<u32> {
    return vec3<u32>(packed & 0x3fffu, (packed >> 14u) & 0x3fffu, packed >> 28u);
}

// Bit k set where `pixels[k]`.
fn quad_bits(pixels: vec4<bool>) -> u32 {
    let bits = select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), pixels);
    return bits.x | bits.y | bits.z | bits.w;
}
