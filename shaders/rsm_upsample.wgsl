// Joint bilateral upsampling of the half-resolution RSM irradiance (rsm.wgsl) at one
// full-resolution pixel, for the composite. It mirrors joint_upsample.wgsl (which is
// tied to the occlusion's size) with the RSM targets' own size: each of the 3×3 low-res
// neighbours is weighted by its distance and by how well its geometry (normal, view
// distance) matches the pixel's tangent plane and normal; with no usable neighbour, the
// nearest one.

const RSM_PLANE_SIGMA: f32 = 0.02;

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
    for (var i = 0; i < 9; i++) {
        let q = base + vec2<i32>(i % 3 - 1, i / 3 - 1);
        if (any(q < vec2<i32>(0)) || any(q >= low_size)) {
            continue;
        }
        let geometry = textureLoad(geometry_low, q, i32(id.z), 0);
        if (!(geometry.w > 0.0)) {
            continue;
        }
        let fq = full_res_pixel(vec2<u32>(q), 2u, frame.size);
        let qpos = view_position_from_distance(pixel_uv(fq, frame.size), geometry.w, eye.tangents);
        let offset = vec2<f32>(fq) - vec2<f32>(id.xy);
        let plane = dot(qpos - position, n) * plane_scale;
        let w = exp(-plane * plane) * normal_agreement(n, geometry.xyz) / (1.0 + dot(offset, offset));
        if (w == w && w > 0.0) {
            sum += textureLoad(indirect_low, q, i32(id.z), 0).rgb * w;
            total += w;
        }
    }
    var result = textureLoad(indirect_low, clamp(base, vec2<i32>(0), low_size - 1), i32(id.z), 0).rgb;
    if (total > 1e-20) {
        result = sum / total;
    }
    return max(finite_or_zero3(result), vec3<f32>(0.0));
}
