// SSDO (Ritschel et al. 2009 eq. 1; Belonogov 2018 §4.1): N directions uniform over the
// normal's hemisphere, each covering Δω = 2π/N, with sample points P + λ_i ω_i, λ_i ∈ [0,
// r_max]. A point below the visible surface (its projection moves towards the eye) blocks its
// direction; unblocked directions gather the environment radiance, pre-filtered to its
// first two SH bands (Ritschel et al. 2009 §7.2 asks for a smooth map;
// `Environment::radiance_sh_prefiltered`). That is linear in ω, so Σ L(ω_i) cos θ_i needs
// only the samples' moments Σc and Σcω: four adds per sample, and the colour is
// evaluated once per pixel.
// With the bounce (Ritschel et al. 2009 eq. 2; Belonogov 2018 §4.2), in the same loop, each
// blocking sample's surface sends the direct light stored at its pixel towards P: as eq. 2's
// patch of area π r_max²/N (BOUNCE_PATCH), or through the blocked direction's share of
// the hemisphere, 2π/N, with the receiver's cosine towards the sender (the default;
// settings.rs `BounceForm`). Both scale by the bounce strength.
// Output: rgb = irradiance to multiply by albedo/π; a = cosine-weighted visibility.

// Bindings and `begin_receiver`: occlusion.wgsl.
@group(0) @binding(7) var direct_layers: texture_2d_array<u32>;

// With the bounce, the occluder probe reads the packed direct light (common.wgsl
// `pack_direct`), which carries the view distance as well as the sender's radiance: one
// fetch per sample, as without the bounce.
struct SenderProbe {
    probe: DepthProbe,
    texel: vec4<u32>,
};

fn probe_sender(layer: u32, s: vec3<f32>, eye: Eye) -> SenderProbe {
    var sp: SenderProbe;
    sp.probe = probe_target(s, eye);
    sp.probe.layer = layer;
    if (!sp.probe.valid) {
        // Off this eye's image the other eye's depth still tells whether the direction
        // is blocked; its sender's light is left out (texel 0 sends nothing).
        sp.probe = probe_depth(depth_layers, layer, s, eye);
        sp.texel = vec4<u32>(0u);
        return sp;
    }
    sp.texel = textureLoad(direct_layers, vec2<i32>(sp.probe.pixel), i32(layer), 0);
    sp.probe.distance = direct_distance(sp.texel);
    sp.probe.valid = sp.probe.distance > 0.0;
    sp.probe.surface = probed_surface(sp.probe, eye);
    return sp;
}

// Σ_i c_i L(ω_i) from the view-space moments of the directions ω_i (irradiance.wgsl
// `linear_sum`). Clamped at 0 as the band-limited radiance can ring negative opposite
// a bright sun.
fn gathered_radiance(layer: u32, m0: f32, m1: vec3<f32>) -> vec3<f32> {
    return max(linear_sum(RADIANCE, layer, m0, m1), vec3<f32>(0.0));
}

// Solid angle of a disc of radius² `a` seen on its axis from distance² `d2`:
// 2π (1 − d / √(d² + a)), written without the cancellation at large d. It is the
// patch's A/d² far away and at most 2π (a hemisphere) when the sender touches the
// receiver, where A/d² diverges: Ritschel et al. 2009 clamps d_i there, and a clamp at the
// patch's own size cut much of the bounce from the nearest senders, which carry most of it
// (docs/records/2026-11-29/measurements-in-code.md, ssdo-disc-clamp).
fn disc_solid_angle(d2: f32, a: f32) -> f32 {
    let s = sqrt(d2 + a);
    return 2.0 * PI * a / (s * (s + sqrt(d2)));
}

// Whether this pipeline gathers the bounce (bounce strength 0 builds the variant without).
override BOUNCE: bool = false;
// The bounce in the patch form of Ritschel et al. 2009 eq. 2 instead of the direction form.
override BOUNCE_PATCH: bool = false;

// Depth peeling (Ritschel et al. 2009 §4, passes/peel.rs): the second depth layer, the nearest
// surface behind the first. With PEEL a sample is an occluder only between the two layers,
// inside the object the first layer sees, not merely behind it: no halo around thin objects in
// front of a background. That inside test also replaces the range check: a sample inside
// an object is within r of the receiver, so the object is a neighbour however far its
// front face is. Nothing behind the first layer (depth 0) counts as infinitely thick.
override PEEL: bool = false;
@group(0) @binding(8) var second_layers: texture_depth_2d_array;

fn in_front_of_second_layer(probe: DepthProbe) -> bool {
    let second = textureLoad(second_layers, vec2<i32>(probe.pixel), i32(probe.layer), 0);
    return probe.sample_distance * second < frame.near;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
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
    // Direction form: each direction covers 2π/N of the hemisphere. Patch form: each
    // sender is a patch of area π r_max² / N (Ritschel et al. 2009), seen as a disc of that
    // area facing the receiver, `disc_radius2` its radius².
    let direction_solid_angle = 2.0 * PI / f32(samples);
    let disc_radius2 = ao.radius * ao.radius / f32(samples);
    // Cosine-weighted moments of all and of unblocked directions (view space).
    var all_m1 = vec3<f32>(0.0);
    var visible_m1 = vec3<f32>(0.0);
    var bounce = vec3<f32>(0.0);
    var weight_all = 0.0;
    var weight_visible = 0.0;
    for (var i = 0u; i < samples; i++) {
        let k = kernel[i];
        let omega = frame_rot * k.xyz;
        let cos_theta = k.z;
        let m1 = omega * cos_theta;
        all_m1 += m1;
        weight_all += cos_theta;
        let s = origin + omega * (k.w * ao.range_scale * ao.radius);
        var fetched: SenderProbe;
        if (BOUNCE) {
            fetched = probe_sender(r.layer, s, r.eye);
        } else {
            fetched.probe = probe_depth(depth_layers, r.layer, s, r.eye);
        }
        let probe = fetched.probe;
        var blocked = occludes(probe, r.position, r.normal, bias);
        if (PEEL) {
            blocked = blocked && in_front_of_second_layer(probe);
        } else if (blocked && ao.range_check != 0u && abs(-r.position.z - probe.distance) > ao.radius) {
            // A surface far in front is not a neighbour: the direction stays open.
            blocked = false;
        }
        if (!blocked) {
            visible_m1 += m1;
            weight_visible += cos_theta;
        } else if (BOUNCE) {
            // The sender: the stored surface at the probed pixel.
            let sender = probe.surface;
            let to_receiver = r.position - sender;
            let d2 = dot(to_receiver, to_receiver);
            let dir = to_receiver * inverseSqrt(max(d2, 1e-30));
            let cos_receiver = max(dot(r.normal, -dir), 0.0);
            var weight = cos_receiver * direction_solid_angle;
            if (BOUNCE_PATCH) {
                // The packed texel has no room for the normal: the patch form alone
                // pays a second fetch for it, from the G-buffer.
                let sender_normal = textureLoad(normal_layers, vec2<i32>(probe.pixel), i32(probe.layer), 0).xyz;
                let cos_sender = max(dot(safe_normal(sender_normal, sender), dir), 0.0);
                weight = cos_sender * cos_receiver * disc_solid_angle(d2, disc_radius2);
            }
            bounce += direct_radiance(fetched.texel) * weight;
        }
    }
    // Eq. 1 with Δω = 2π/N estimates ∫ L V cos dω; its N-sample quadrature error
    // (docs/records/2026-11-29/measurements-in-code.md, ssdo-quadrature) and the pre-filter would make SSDO
    // disagree with the unoccluded ambient on an open surface. So the samples decide only
    // which share of the incoming light is blocked, per colour channel, and that share
    // scales the exact SH irradiance: an open plane gets exactly the ambient of the other
    // techniques, at any N.
    let visibility = select(1.0, weight_visible / weight_all, weight_all > 1e-20);
    let gathered_all = gathered_radiance(r.layer, weight_all, all_m1);
    let gathered_visible = gathered_radiance(r.layer, weight_visible, visible_m1);
    let share = select(vec3<f32>(visibility), gathered_visible / gathered_all, gathered_all > vec3<f32>(1e-20));
    var unoccluded = vec3<f32>(0.0);
    if (frame.has_environment != 0u) {
        unoccluded = environment_irradiance(r.layer, r.normal);
    }
    let direct_occlusion = mix(unoccluded, unoccluded * share, clamp(ao.strength, 0.0, 1.0));
    let irradiance = direct_occlusion + bounce * ao.bounce;
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    textureStore(ao_out, vec2<i32>(id.xy), i32(r.layer), chain_texel(vec4<f32>(finite_or_zero3(irradiance), result)));
}
