// SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3): N points in a normal-oriented
// hemisphere around each pixel's view-space position, most of them close to it; a point is
// occluded when the depth buffer holds a surface in front of it. Applied to the ambient term
// only.

// Bindings and `begin_receiver`: occlusion.wgsl; the right eye's reuse of the left eye:
// occlusion/right_eye.wgsl.

// A copied value carries no light (AO alone).
fn reused_light(value: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) invocation: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let id = estimated_pixel(invocation, group, local);
    let r = begin_receiver(id);
    if (!r.valid) {
        return;
    }
    let frame_rot = tangent_frame(r.normal, kernel_rotation(stereo_noise_pixel(r.pixel, frame.size, r.layer, r.eye, r.position), ao.noise) + ao.frame_angle);
    let bias = ao.bias * ao.radius;
    let origin = r.position + r.normal * bias;
    // Fewer samples towards the image's edges with fixed foveation (occlusion.wgsl): a
    // prefix of the low-discrepancy kernel.
    let samples = foveated_count(max(ao.samples, 1u), foveation_rate(id.xy, r.layer), id.xy);
    var occlusion = 0.0;
    for (var i = 0u; i < samples; i++) {
        let k = kernel[i];
        let s = origin + frame_rot * k.xyz * (k.w * ao.range_scale * ao.radius);
        let probe = probe_depth(depth_layers, r.layer, s, r.eye);
        if (occludes(probe, r.position, r.normal, bias)) {
            var weight = 1.0;
            if (ao.range_check != 0u) {
                // Depth constraint: occluders far in front of the pixel (a foreground
                // object, not a neighbour) fade out instead of casting a halo.
                weight = smoothstep(0.0, 1.0, ao.radius / max(abs(-r.position.z - probe.distance), 1e-20));
            }
            occlusion += weight;
        }
    }
    let visibility = 1.0 - occlusion / f32(samples);
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    store_occlusion(id, vec4<f32>(0.0, 0.0, 0.0, result));
}
