// SSDO (seed 002 eq. 1; seed 003 §4.1): N directions uniform over the normal's
// hemisphere, each covering Δω = 2π/N, with sample points P + λ_i ω_i, λ_i ∈ [0, r_max].
// A point below the visible surface (its projection moves towards the eye) blocks its
// direction; unblocked directions gather the environment radiance, pre-filtered as a
// Hann-windowed SH9 (a smooth map needs no per-sample texture fetch, seed 002 §7.2).
// With the bounce (seed 002 eq. 2; seed 003 §4.2), in the same loop, each blocking
// sample's surface becomes a sender patch of area π r_max²/N × bounce strength that
// reflects the direct light stored at its pixel towards P.
// Output: rgb = irradiance to multiply by albedo/π; a = cosine-weighted visibility.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<storage, read> kernel: array<vec4<f32>>;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var direct_layers: texture_2d_array<f32>;
@group(0) @binding(6) var ao_out: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(7) var geometry_out: texture_storage_2d_array<rgba32float, write>;

// Whether this pipeline gathers the bounce (bounce strength 0 builds the variant without).
override BOUNCE: bool = false;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return;
    }
    let layer = id.z;
    let eye = frame.eyes[layer];
    let fp = full_res_pixel(id.xy, ao.scale, frame.size);
    let depth = textureLoad(depth_layers, vec2<i32>(fp), i32(layer), 0);
    if (depth <= 0.0) {
        textureStore(ao_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
        textureStore(geometry_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(0.0));
        return;
    }
    let position = load_view_position(depth, fp, eye, frame.size, frame.near);
    let n = safe_normal(textureLoad(normal_layers, vec2<i32>(fp), i32(layer), 0).xyz, position);
    textureStore(geometry_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(n, -position.z));
    let frame_rot = tangent_frame(n, kernel_rotation(fp, ao.noise));
    let world_from_view = mat3x3<f32>(eye.world_from_view[0].xyz, eye.world_from_view[1].xyz, eye.world_from_view[2].xyz);
    let bias = ao.bias * ao.radius;
    let origin = position + n * bias;
    let samples = max(ao.samples, 1u);
    // Sender patch area (π r_max² / N) scaled by the bounce strength; distances are
    // clamped to the patch's own size so the 1/d² form factor stays bounded.
    let patch_area = PI * ao.radius * ao.radius / f32(samples);
    let min_d2 = patch_area;
    var gathered_all = vec3<f32>(0.0);
    var gathered_visible = vec3<f32>(0.0);
    var bounce = vec3<f32>(0.0);
    var weight_all = 0.0;
    var weight_visible = 0.0;
    for (var i = 0u; i < samples; i++) {
        let k = kernel[i];
        let omega = frame_rot * k.xyz;
        let cos_theta = k.z;
        var incoming = vec3<f32>(0.0);
        if (frame.has_environment != 0u) {
            incoming = sh_eval(frame.radiance_sh, world_from_view * omega);
        }
        gathered_all += incoming * cos_theta;
        weight_all += cos_theta;
        let s = origin + omega * (k.w * ao.radius);
        let probe = probe_depth(depth_layers, layer, s, eye);
        var blocked = occludes(probe, s, position, n, eye, bias);
        if (blocked && ao.range_check != 0u && abs(-position.z - probe.distance) > ao.radius) {
            // A surface far in front is not a neighbour: the direction stays open.
            blocked = false;
        }
        if (!blocked) {
            gathered_visible += incoming * cos_theta;
            weight_visible += cos_theta;
        } else if (BOUNCE) {
            let sender = load_view_position(frame.near / probe.distance, probe.pixel, eye, frame.size, frame.near);
            let sender_n = safe_normal(textureLoad(normal_layers, vec2<i32>(probe.pixel), i32(layer), 0).xyz, sender);
            let to_receiver = position - sender;
            let d2 = max(dot(to_receiver, to_receiver), min_d2);
            let dir = to_receiver * inverseSqrt(max(dot(to_receiver, to_receiver), 1e-30));
            let cos_sender = max(dot(sender_n, dir), 0.0);
            let cos_receiver = max(dot(n, -dir), 0.0);
            let radiance = max(textureLoad(direct_layers, vec2<i32>(probe.pixel), i32(layer), 0).rgb, vec3<f32>(0.0));
            bounce += radiance * (cos_sender * cos_receiver / d2);
        }
    }
    // Eq. 1 with Δω = 2π/N estimates ∫ L V cos dω; its N-sample quadrature error (+16 %
    // at N = 12) and the pre-filter would make SSDO disagree with the unoccluded ambient
    // on an open surface. So the samples decide only which share of the incoming light
    // is blocked, per colour channel, and that share scales the exact SH irradiance: an
    // open plane gets exactly the ambient of the other techniques, at any N.
    let visibility = select(1.0, weight_visible / weight_all, weight_all > 1e-20);
    let share = select(vec3<f32>(visibility), gathered_visible / gathered_all, gathered_all > vec3<f32>(1e-20));
    var unoccluded = vec3<f32>(0.0);
    if (frame.has_environment != 0u) {
        unoccluded = sh_eval(frame.irradiance_sh, world_from_view * n);
    }
    let direct_occlusion = mix(unoccluded, unoccluded * share, clamp(ao.strength, 0.0, 1.0));
    let irradiance = direct_occlusion + bounce * (patch_area * ao.bounce);
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    textureStore(ao_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(finite_or_zero3(irradiance), result));
}
