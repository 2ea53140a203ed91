// Joint bilateral upsampling (Kopf et al. 2007; seed 000: 3×3, not separated) of
// half-resolution occlusion at one full-resolution pixel, shared by the upsample pass
// (which writes AoFull for debug images and tests) and the composite (which upsamples
// inline, so a frame needs no full-resolution occlusion target). Each low-res
// neighbour is weighted by its distance to the pixel and by how well its geometry
// (normal and distance in AoGeometry, from the full-res pixel it was computed at)
// matches: tangent-plane distance and normal. Odd sizes work because low-res pixel q
// stands for full-res pixel min(2q, size − 1). The low-res size is the texture's own, so
// any half-resolution target (occlusion, the RSM bounce) upsamples with it.

const PLANE_SIGMA: f32 = 0.02;
// Below this plane-and-normal agreement of any of the 2×2 nearest samples, the pixel is
// treated as an edge and gets the full 3×3.
const EDGE_AGREEMENT: f32 = 0.5;

struct Tap {
    value: vec4<f32>,
    // Joint bilateral weight (0 for a sample off the target or on the sky).
    weight: f32,
    // The geometric part of the weight: 1 for the same plane and normal.
    agreement: f32,
};

// Low-res sample `q` seen from full-res pixel `id` at `position` with normal `n`.
fn upsample_tap(
    geometry_low: texture_2d_array<f32>,
    occlusion_low: texture_2d_array<f32>,
    q: vec2<i32>,
    id: vec3<u32>,
    eye: Eye,
    position: vec3<f32>,
    n: vec3<f32>,
    plane_scale: f32,
) -> Tap {
    var t: Tap;
    t.weight = 0.0;
    t.agreement = 0.0;
    if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(textureDimensions(occlusion_low)))) {
        return t;
    }
    let geometry = textureLoad(geometry_low, q, i32(id.z), 0);
    if (!(geometry.w > 0.0)) {
        return t;
    }
    let fq = full_res_pixel(vec2<u32>(q), 2u, frame.size);
    let qpos = view_position_from_distance(pixel_uv(fq, frame.size), geometry.w, eye.tangents);
    // Full-res distance between this pixel's centre and the sample's.
    let offset = vec2<f32>(fq) - vec2<f32>(id.xy);
    let plane = dot(qpos - position, n) * plane_scale;
    t.agreement = exp(-plane * plane) * normal_agreement(n, geometry.xyz);
    let w = t.agreement / (1.0 + dot(offset, offset));
    if (w == w) {
        t.weight = w;
        t.value = textureLoad(occlusion_low, q, i32(id.z), 0);
    }
    return t;
}

// The occlusion at full-res pixel `id` (seen at `position` with normal `n`) from the
// half-resolution occlusion and its geometry.
fn joint_upsample(
    geometry_low: texture_2d_array<f32>,
    occlusion_low: texture_2d_array<f32>,
    id: vec3<u32>,
    eye: Eye,
    position: vec3<f32>,
    n: vec3<f32>,
) -> vec4<f32> {
    let base = vec2<i32>(id.xy / 2u);
    let plane_scale = 1.0 / (PLANE_SIGMA * -position.z);
    // The 2×2 low-res samples around this pixel first; where they all agree with its
    // geometry (a smooth surface) that is the answer, else (an edge) the seed's full 3×3.
    var sum = vec4<f32>(0.0);
    var total = 0.0;
    var agree = 1.0;
    for (var i = 0; i < 4; i++) {
        let t = upsample_tap(geometry_low, occlusion_low, base + vec2<i32>(i & 1, i >> 1u), id, eye, position, n, plane_scale);
        sum += t.value * t.weight;
        total += t.weight;
        agree = min(agree, t.agreement);
    }
    if (agree < EDGE_AGREEMENT) {
        for (var i = 0; i < 5; i++) {
            // (-1,-1) (0,-1) (1,-1) (-1,0) (-1,1): the rest of the 3×3.
            let offset = select(vec2<i32>(-1, i - 2), vec2<i32>(i - 1, -1), i < 3);
            let t = upsample_tap(geometry_low, occlusion_low, base + offset, id, eye, position, n, plane_scale);
            sum += t.value * t.weight;
            total += t.weight;
        }
    }
    // When every weight vanishes, the nearest low-res sample.
    var result = textureLoad(occlusion_low, min(base, vec2<i32>(textureDimensions(occlusion_low)) - 1), i32(id.z), 0);
    if (total > 1e-20) {
        result = sum / total;
    }
    return vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
}
