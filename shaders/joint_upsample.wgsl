// Joint bilateral upsampling (Kopf et al. 2007; seed 000: 3×3, not separated) of
// half-resolution occlusion, shared by the upsample pass (which writes AoFull for debug
// images and tests) and the composite (which upsamples inline, so a frame needs no
// full-resolution occlusion target). One invocation upsamples the quad of 2×2 full-res
// pixels 2b + {0, 1}² of low-res sample b: all four have the same 2×2 (and 3×3)
// low-res neighbourhood, so each sample is fetched once per quad instead of once per
// pixel. On lavapipe the fetches, not the weights, are what upsampling costs: per pixel
// it went from 18.2 to 11.5 ms at 540×600 (Sibenik). Each low-res neighbour is weighted
// by its distance to the pixel and by how well its geometry (normal and distance in
// AoGeometry, from the full-res pixel it was computed at) matches: tangent-plane
// distance and normal. Odd sizes work because low-res pixel q
// stands for full-res pixel min(2q, size − 1). The low-res size is the texture's own, so
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

fn low_res_sample(
    geometry_low: texture_2d_array<f32>,
    value_low: texture_2d_array<f32>,
    q: vec2<i32>,
    layer: u32,
    tangents: vec4<f32>,
) -> LowResSample {
    let last = vec2<i32>(textureDimensions(value_low)) - 1;
    let clamped = clamp(q, vec2<i32>(0), last);
    let geometry = textureLoad(geometry_low, clamped, i32(layer), 0);
    let fq = full_res_pixel(vec2<u32>(clamped), 2u, frame.size);
    var s: LowResSample;
    s.valid = select(0.0, 1.0, all(q == clamped) && geometry.w > 0.0);
    s.position = view_position_from_distance(pixel_uv(fq, frame.size), geometry.w, tangents);
    s.normal = geometry.xyz;
    s.value = textureLoad(value_low, clamped, i32(layer), 0);
    return s;
}

// One full-res pixel's running joint bilateral sum.
struct UpsamplePixel {
    position: vec3<f32>,
    n: vec3<f32>,
    // n·position × plane_scale: a sample's plane distance is then one dot and a subtract.
    plane_offset: f32,
    plane_scale: f32,
    sum: vec4<f32>,
    total: f32,
    // The least geometric agreement of the samples so far (edge test).
    agree: f32,
    // The value of low-res sample b itself, the answer when every weight vanishes.
    nearest: vec4<f32>,
};

// Pixel `k` (0..3) of the quad of low-res sample `b`. Pixels past an odd edge repeat the
// last row or column; callers skip their store.
fn quad_pixel(b: vec2<u32>, k: u32) -> vec2<u32> {
    return min(b * 2u + vec2<u32>(k & 1u, k >> 1u), frame.size - vec2<u32>(1u));
}

// The running sum of full-res `pixel` of eye `eye`, whose stored depth and normal are
// `depth` and `normal` (G-buffer): its view position and normal. A sky pixel (depth 0)
// gets a far-away position; its result is not used.
fn upsample_pixel(pixel: vec2<u32>, eye: Eye, depth: f32, normal: vec3<f32>) -> UpsamplePixel {
    let position = load_view_position(max(depth, 1e-30), pixel, eye, frame.size, frame.near);
    var px: UpsamplePixel;
    px.position = position;
    px.n = safe_normal(normal, position);
    px.plane_scale = 1.0 / (PLANE_SIGMA * -position.z);
    px.plane_offset = dot(px.n, position) * px.plane_scale;
    px.sum = vec4<f32>(0.0);
    px.total = 0.0;
    px.agree = 1.0;
    px.nearest = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    return px;
}

// Weighs sample `s` into pixel `px`: its distance to the pixel's tangent plane and its
// normal agreement (the geometric part), times `spatial`, 1 / (1 + the squared full-res
// pixel distance between them) (`spatial_weight`).
fn add_sample(pixel: UpsamplePixel, s: LowResSample, spatial: f32) -> UpsamplePixel {
    var px = pixel;
    let plane = dot(s.position, px.n) * px.plane_scale - px.plane_offset;
    let agreement = s.valid * exp(-plane * plane) * normal_agreement(px.n, s.normal);
    let w = agreement * spatial;
    let ok = w == w;
    px.sum += s.value * select(0.0, w, ok);
    px.total += select(0.0, w, ok);
    px.agree = min(px.agree, select(0.0, agreement, ok));
    return px;
}

// 1 / (1 + d²) for the full-res distance d between pixel k of the quad of b and low-res
// sample b + `offset`, computed at full-res pixel 2(b + offset): a constant of the
// unrolled loops (a sample clamped at the border is invalid and gets weight 0 anyway).
fn spatial_weight(offset: vec2<i32>, k: i32) -> f32 {
    let d = vec2<f32>(2 * offset - vec2<i32>(k & 1, k >> 1u));
    return 1.0 / (1.0 + dot(d, d));
}

// The pixel's upsampled value; the nearest sample's when every weight vanished.
fn upsampled(px: UpsamplePixel) -> vec4<f32> {
    var result = px.nearest;
    if (px.total > 1e-20) {
        result = px.sum / px.total;
    }
    return vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
}

// Upsamples the four pixels of the quad of low-res sample `b` (their positions and
// normals already in `pixels`): the 2×2 samples b + {0, 1}² first; where any pixel
// disagrees with them (an edge), the rest of the 3×3 around b for the pixels that do.
fn upsample_quad(
    geometry_low: texture_2d_array<f32>,
    value_low: texture_2d_array<f32>,
    b: vec2<i32>,
    layer: u32,
    tangents: vec4<f32>,
    quad: array<UpsamplePixel, 4>,
) -> array<UpsamplePixel, 4> {
    var pixels = quad;
    for (var i = 0; i < 4; i++) {
        let s = low_res_sample(geometry_low, value_low, b + vec2<i32>(i & 1, i >> 1u), layer, tangents);
        for (var k = 0; k < 4; k++) {
            if (i == 0) {
                pixels[k].nearest = s.value;
            }
            pixels[k] = add_sample(pixels[k], s, spatial_weight(vec2<i32>(i & 1, i >> 1u), k));
        }
    }
    let edge = min(min(pixels[0].agree, pixels[1].agree), min(pixels[2].agree, pixels[3].agree));
    if (edge < EDGE_AGREEMENT) {
        // Which pixels take the 3×3, decided before any of it is added.
        var needs = 0u;
        for (var k = 0; k < 4; k++) {
            needs |= select(0u, 1u << u32(k), pixels[k].agree < EDGE_AGREEMENT);
        }
        for (var i = 0; i < 5; i++) {
            // (-1,-1) (0,-1) (1,-1) (-1,0) (-1,1): the rest of the 3×3.
            let offset = select(vec2<i32>(-1, i - 2), vec2<i32>(i - 1, -1), i < 3);
            let s = low_res_sample(geometry_low, value_low, b + offset, layer, tangents);
            for (var k = 0; k < 4; k++) {
                if ((needs & (1u << u32(k))) != 0u) {
                    pixels[k] = add_sample(pixels[k], s, spatial_weight(offset, k));
                }
            }
        }
    }
    return pixels;
}
