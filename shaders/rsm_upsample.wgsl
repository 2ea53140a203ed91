// The half-resolution RSM irradiance (rsm.wgsl) at one full-resolution pixel, for the
// composite: the same 3×3 joint bilateral upsampling as the occlusion's
// (joint_upsample.wgsl), on the RSM targets (irradiance in rgb, its geometry as
// AoGeometry lays it out), never negative.

fn rsm_upsample(
    geometry_low: texture_2d_array<f32>,
    indirect_low: texture_2d_array<f32>,
    id: vec3<u32>,
    eye: Eye,
    position: vec3<f32>,
    n: vec3<f32>,
) -> vec3<f32> {
    return max(joint_upsample(geometry_low, indirect_low, id, eye, position, n).rgb, vec3<f32>(0.0));
}
