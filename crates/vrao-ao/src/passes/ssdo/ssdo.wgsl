// SSDO's light on GTAO's march (gtao.wgsl calls these hooks; passes/ssdo/mod.rs): the
// seeds' directional occlusion (Ritschel et al. 2009 eq. 1) and one bounce (eq. 2) with
// the visibility bitmask's sectors in place of point samples (Therrien, Levesque and
// Gilet 2023). Every sector of a slice carries the same share of the cosine-weighted
// hemisphere (gtao.wgsl), so a share of sectors is a share of the irradiance.
//
// Environment (eq. 1): the unoccluded irradiance E(n) of the environment's SH, scaled per
// colour channel by the share of it that arrives through the unoccluded sectors. That
// share is the occlusion's visibility V (GTAO's, so an open plane gets exactly E(n))
// times the ratio of the mean pre-filtered radiance over the unoccluded directions to its
// mean over all: light from a bright side blocked darkens more than V says. The means
// come from LIGHT_DIRECTIONS directions per slice, evenly spaced in angle (jittered per
// pixel), each weighed by its cosine and its slice's measure and counted unoccluded
// where its sector's bit is clear (or it lies in the open gap around V).
//
// Bounce (eq. 2): a sample that covers sectors no nearer sample covered sends the direct
// light stored at its pixel (outgoing radiance L_pixel, the sender's albedo in it)
// through them when its surface faces the receiver: E_b = π Σ_slices w_s Σ_senders
// L_pixel · facing · (new sectors / 32) / Σ_slices w_s. The sectors are the solid angle
// and the cosine at once; L_pixel is a Lambertian sender's radiance in every direction
// it faces. Senders beyond the inner border (the other eye's depth) send nothing.
//
// Output rgb: irradiance to multiply by albedo/π (the composite's directional mode).

// The packed direct light (common.wgsl `pack_direct`): the bounce's senders.
@group(0) @binding(14) var direct_layers: texture_2d_array<u32>;

// Whether this pipeline gathers the bounce (bounce strength 0 builds the one without).
override BOUNCE: bool = false;

// Directions per slice that weigh the environment's radiance (jittered per pixel: the
// denoise averages 16 pixels' offsets).
const LIGHT_DIRECTIONS: u32 = 4u;

struct GatheredLight {
    // Σ over slices of |projected normal| × the directions' cosine weights, and of the
    // weights × the directions (view space): over all directions, and the unoccluded ones.
    all_m0: f32,
    all_m1: vec3<f32>,
    visible_m0: f32,
    visible_m1: vec3<f32>,
    // This slice's senders so far (Σ L · facing · new sectors), and Σ_s w_s × that / 32.
    slice_bounce: vec3<f32>,
    bounce: vec3<f32>,
    // Where this pixel's directions start within their first step, 0..1.
    jitter: f32,
};

fn begin_light(noise: f32) -> GatheredLight {
    var light: GatheredLight;
    light.all_m0 = 0.0;
    light.all_m1 = vec3<f32>(0.0);
    light.visible_m0 = 0.0;
    light.visible_m1 = vec3<f32>(0.0);
    light.slice_bounce = vec3<f32>(0.0);
    light.bounce = vec3<f32>(0.0);
    // A fourth value of GTAO's noise tile (13 is prime to 16).
    light.jitter = fract(noise * 13.0 + 0.40625);
    return light;
}

// A sample at full-res `pixel` whose slab newly covered the sectors `newly`: with the
// bounce, its surface `sender` sends its direct light through them towards `p` when it
// faces `p` (a back face sends nothing; a ramp over the first 6° keeps a face turning
// edge-on from popping).
fn gather_sample(light: ptr<function, GatheredLight>, newly: u32, pixel: vec2<u32>, layer: u32, sender: vec3<f32>, p: vec3<f32>) {
    if (!BOUNCE || newly == 0u) {
        return;
    }
    let n = safe_normal(textureLoad(normal_layers, vec2<i32>(pixel), i32(layer), 0).xyz, sender);
    let to_receiver = p - sender;
    let facing = clamp(10.0 * dot(n, to_receiver) * inverseSqrt(max(dot(to_receiver, to_receiver), 1e-30)), 0.0, 1.0);
    if (facing <= 0.0) {
        return;
    }
    let texel = textureLoad(direct_layers, vec2<i32>(pixel), i32(layer), 0);
    (*light).slice_bounce += direct_radiance(texel) * (facing * f32(countOneBits(newly)));
}

// Whether the direction at sector coordinate u is unoccluded after `march`.
fn open_at(march: March, u: f32, offset: f32) -> bool {
    if (u > march.near_minus && u < march.near_plus) {
        return true;
    }
    let bit = u32(clamp(floor(u * SECTORS + offset), 0.0, SECTORS - 1.0));
    return ((march.occluded >> bit) & 1u) == 0u;
}

fn end_slice(
    light: ptr<function, GatheredLight>, slice: Slice, march: March, offset: f32, projected_len: f32, weight: f32, view: vec3<f32>,
) {
    if (BOUNCE) {
        (*light).bounce += (*light).slice_bounce * (weight / SECTORS);
        (*light).slice_bounce = vec3<f32>(0.0);
    }
    if (frame.has_environment == 0u) {
        // No environment: nothing to weigh (uniform across the dispatch).
        return;
    }
    // Directions θ_j = θ_min + φ_j, φ_j = (j + jitter) Δ over the half circle; the slice's
    // cosine-weighted measure there is |sin θ| cos(θ − γ) = |sin θ| sin φ.
    let delta = PI / f32(LIGHT_DIRECTIONS);
    let phi0 = (*light).jitter * delta;
    var phi = vec2<f32>(cos(phi0), sin(phi0));
    let turn = vec2<f32>(cos(delta), sin(delta));
    for (var j = 0u; j < LIGHT_DIRECTIONS; j++) {
        if (j > 0u) {
            phi = vec2<f32>(phi.x * turn.x - phi.y * turn.y, phi.x * turn.y + phi.y * turn.x);
        }
        // cos θ_min = sin γ, sin θ_min = −cos γ.
        let cos_t = slice.sin_gamma * phi.x + slice.cos_gamma * phi.y;
        let sin_t = slice.sin_gamma * phi.y - slice.cos_gamma * phi.x;
        let w = projected_len * abs(sin_t) * max(phi.y, 0.0);
        let omega = sin_t * slice.t + cos_t * view;
        // u(θ) as gtao.wgsl `sector_coordinate`: (G(θ_min) ± G(θ)) / total, with
        // G(θ) = ¼ (cos γ − cos(2θ − γ) + 2θ sin γ) on the half of θ's sign.
        let theta = slice.theta_min + phi0 + f32(j) * delta;
        let cos_2t_g = (cos_t * cos_t - sin_t * sin_t) * slice.cos_gamma + 2.0 * sin_t * cos_t * slice.sin_gamma;
        let g = 0.25 * (slice.cos_gamma - cos_2t_g + 2.0 * theta * slice.sin_gamma);
        let side = select(-1.0, 1.0, theta >= 0.0);
        let u = clamp((slice.g_min + side * g) * slice.inv_total, 0.0, 1.0);
        (*light).all_m0 += w;
        (*light).all_m1 += w * omega;
        if (open_at(march, u, offset)) {
            (*light).visible_m0 += w;
            (*light).visible_m1 += w * omega;
        }
    }
}

// The unoccluded irradiance E(n) of the frame's environment (0 without one).
fn unoccluded_irradiance(r: Receiver) -> vec3<f32> {
    if (frame.has_environment == 0u) {
        return vec3<f32>(0.0);
    }
    return environment_irradiance(r.layer, r.normal);
}

fn light_result(light: GatheredLight, r: Receiver, visibility: f32, total: f32) -> vec3<f32> {
    let unoccluded = unoccluded_irradiance(r);
    // The mean pre-filtered radiance over all directions and over the unoccluded ones
    // (it is linear in the direction: irradiance.wgsl `linear_sum`). Clamped at 0 as the
    // band-limited radiance can ring negative opposite a bright sun.
    var tilt = vec3<f32>(1.0);
    if (light.all_m0 > 1e-20 && light.visible_m0 > 1e-6 * light.all_m0) {
        let mean_all = max(linear_sum(RADIANCE, r.layer, 1.0, light.all_m1 / light.all_m0), vec3<f32>(0.0));
        let mean_visible = max(linear_sum(RADIANCE, r.layer, 1.0, light.visible_m1 / light.visible_m0), vec3<f32>(0.0));
        tilt = select(vec3<f32>(1.0), mean_visible / mean_all, mean_all > vec3<f32>(1e-20));
    }
    // What arrives cannot exceed what the whole hemisphere sends.
    let share = min(visibility * tilt, vec3<f32>(1.0));
    let environment = mix(unoccluded, unoccluded * share, clamp(ao.strength, 0.0, 1.0));
    var bounce = vec3<f32>(0.0);
    if (BOUNCE && total > 1e-12) {
        bounce = light.bounce * (PI / total) * ao.bounce;
    }
    return finite_or_zero3(environment + bounce);
}

// A receiver whose radius lies within its pixel: nothing occludes it, nothing bounces.
fn open_light(r: Receiver) -> vec3<f32> {
    return finite_or_zero3(unoccluded_irradiance(r));
}

// The right eye takes the left eye's light with its AO: irradiance is the surface
// point's, not the eye's.
fn reused_light(left: vec4<f32>) -> vec3<f32> {
    return left.rgb;
}
