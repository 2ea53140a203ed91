// Joint bilateral upsampling of the half-resolution RSM irradiance (rsm.wgsl) at one
// full-resolution pixel, for the composite. It mirrors joint_upsample.wgsl (which is
// tied to the occlusion's size) with the RSM targets' own size: each low-res neighbour is
// weighted by its distance and by how well its geometry (normal, view distance) matches
// the pixel's tangent plane and normal. The 2×2 nearest first; where one of them does
// not agree (an edge), the rest of the 3×3; with no usable neighbour, the nearest one.

const RSM_PLANE_SIGMA: f32 = 0.02;
const RSM_EDGE_AGREEMENT: f32 = 0.5;

struct RsmTap {
    value: vec3<f32>,
    weight: f32,
    agreement: f32,
};

fn rsm_tap(
    geometry_low: texture_2d_array<f32>,
    indirect_low: texture_2d_array<f32>,
    q: vec2<i32>,
    id: vec3<u32>,
    eye: Eye,
    position: vec3<f32>,
    n: vec3<f32>,
    plane_scale: f32,
) -> RsmTap {
    var t: RsmTap;
    t.value = vec3<f32>(0.0);
    t.weight = 0.0;
    t.agreement = 0.0;
    if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(textureDimensions(indirect_low)))) {
        return t;
    }
    let geometry = textureLoad(geometry_low, q, i32(id.z), 0);
    if (!(geometry.w > 0.0)) {
        return t;
    }
    let fq = full_res_pixel(vec2<u32>(q), 2u, frame.size);
    let qpos = view_position_from_distance(pixel_uv(fq, frame.size), geometry.w, eye.tangents);
    let offset = vec2<f32>(fq) - vec2<f32>(id.xy);
    let plane = dot(qpos - position, n) * plane_scale;
    t.agreement = exp(-plane * plane) * normal_agreement(n, geometry.xyz);
    let w = t.agreement / (1.0 + dot(offset, offset));
    if (w == w && w > 0.0) {
        t.weight = w;
        t.value = textureLoad(indirect_low, q, i32(id.z), 0).rgb;
    }
    return t;
}

fn rsm_upsample(
    geometry_low: texture_2d_array<f32>,
    indirect_low: texture_2d_array<f32>,
    id: vec3<u32>,
    eye: Eye,
    position: vec3<f32>,
    n: vec3<f32>,
) -> vec3<f32> {
    let low_size = vec2<i32>(textureDimensions(indirect_low));
    let base = vec2<i32>(id.xy / 2u);
    let plane_scale = 1.0 / (RSM_PLANE_SIGMA * -position.z);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    var agree = 1.0;
    for (var i = 0; i < 4; i++) {
        let t = rsm_tap(geometry_low, indirect_low, base + vec2<i32>(i & 1, i >> 1u), id, eye, position, n, plane_scale);
        sum += t.value * t.weight;
        total += t.weight;
        agree = min(agree, t.agreement);
    }
    if (agree < RSM_EDGE_AGREEMENT) {
        for (var i = 0; i < 5; i++) {
            // (-1,-1) (0,-1) (1,-1) (-1,0) (-1,1): the rest of the 3×3.
            let offset = select(vec2<i32>(-1, i - 2), vec2<i32>(i - 1, -1), i < 3);
            let t = rsm_tap(geometry_low, indirect_low, base + offset, id, eye, position, n, plane_scale);
            sum += t.value * t.weight;
            total += t.weight;
        }
    }
    var result = textureLoad(indirect_low, clamp(base, vec2<i32>(0), low_size - 1), i32(id.z), 0).rgb;
    if (total > 1e-20) {
        result = sum / total;
    }
    return max(finite_or_zero3(result), vec3<f32>(0.0));
}
