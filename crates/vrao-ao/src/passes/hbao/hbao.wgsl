// HBAO (Belonogov 2018 §3.3, after Bavoil, Sainz and Dimitrov 2008): D screen directions,
// rotated per pixel, each ray-marched S steps through the depth buffer. A sample above
// the current horizon raises it and adds its occlusion; samples beyond R do not count
// (the hard cut-off of every technique's target; Belonogov 2018's falloff W = 1 − r/R made
// HBAO lighter than that target everywhere). Samples off the image are looked up in
// the other eye's layer. Horizon angles are measured from the tangent plane (the normal
// is known), and increments use sin²h instead of sin h: the cosine-weighted form of
// eq. 3.2, so HBAO estimates the same cosine-weighted visibility as the reference.

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
    // The radius R in pixels at this depth (tangent span per pixel × distance).
    let metres_per_pixel = (r.eye.tangents.y - r.eye.tangents.x) / f32(frame.size.x) * -r.position.z;
    let radius_px = ao.radius / max(metres_per_pixel, 1e-30);
    // Fewer directions, then steps, towards the image's edges with fixed foveation
    // (occlusion.wgsl).
    let counts = foveated_march(max(ao.directions, 1u), max(ao.steps, 1u), foveation_rate(id.xy, r.layer), id.xy);
    let directions = counts.x;
    let steps = counts.y;
    // Never further than the image's diagonal.
    let march_px = min(radius_px * ao.range_scale, f32(frame.size.x + frame.size.y));
    let rotation = kernel_rotation(stereo_noise_pixel(r.pixel, frame.size, r.layer, r.eye, r.position), ao.noise) + ao.frame_angle;
    let jitter = fract(rotation * 0.1591549 * 7.0);
    // Angle bias: horizons below this elevation do not count (tessellation, noise).
    let sin_bias = min(5.0 * ao.bias, 0.9);
    var occlusion = 0.0;
    for (var d = 0u; d < directions; d++) {
        let angle = rotation + 2.0 * PI * f32(d) / f32(directions);
        let dir = vec2<f32>(cos(angle), sin(angle));
        var max_sin = sin_bias;
        var previous_distance = -r.position.z;
        for (var s = 0u; s < steps; s++) {
            // Steps crowd towards the pixel (quadratically, the first within a few
            // pixels), so the horizon rises right at contact lines instead of a band
            // one step away.
            let t = (f32(s) + jitter) / f32(steps);
            let offset = dir * max(t * t * march_px, f32(s) + 1.0);
            let q = vec2<f32>(r.pixel) + vec2<f32>(0.5) + offset;
            let surface = surface_at(q, r.layer, r.eye, previous_distance);
            if (surface.w == 0.0) {
                continue;
            }
            previous_distance = -surface.z;
            let h = surface.xyz - r.position;
            let dist = length(h);
            if (dist < 1e-20 || dist > ao.radius) {
                continue;
            }
            // Everything below the horizon within r blocks, with no falloff: HBAO
            // estimates the hard cut-off visibility like every technique.
            let sin_h = dot(h, r.normal) / dist;
            if (sin_h > max_sin) {
                occlusion += sin_h * sin_h - max_sin * max_sin;
                max_sin = sin_h;
            }
        }
    }
    let visibility = 1.0 - occlusion / f32(directions);
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    store_occlusion(id, vec4<f32>(0.0, 0.0, 0.0, result));
}
