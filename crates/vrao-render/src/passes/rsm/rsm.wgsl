// One bounce of directional light from reflective shadow maps (Dachsbacher & Stamminger
// 2005; Lin's NCTU thesis §3.3), at half resolution per axis. Each map texel is a virtual point
// light (VPL) q with flux Φ_q; a receiver p gathers
//     E_p = Σ_q Φ_q / π · max(0, N_p·D) · max(0, N_q·(−D)) / ‖q − p‖²,  D = (q − p)/‖q − p‖
// (Lin's NCTU thesis eqs. 9–10 with the 1/π a Lambertian VPL's intensity Φ cos θ / π carries).
// The sum runs over VPLs sampled in a disk of radius R around p's projection into the
// map: sample k lies in the k-th of N equal-width rings (so samples crowd towards the
// centre, as in the original RSM) at an angle stepping by the golden angle, and stands
// for the area of its ring, 2π r R / N: each ring's estimate is unbiased. The whole
// pattern turns per pixel (interleaved) and per frame (Lin's NCTU thesis: "we always have to
// rotate the sampling pattern"; the frame index comes from the pass's own counter), and
// the rings shift by a per-pixel jitter. VPL visibility is not tested (as in the
// original RSM). A VPL within its own area of p counts as a disk, Φ/(π d² + A) instead
// of Φ/(π d²), so close VPLs stay finite.
// Writes the irradiance (rgb) and the pixel's geometry (normal, view distance; the form
// of AoGeometry) for the composite's joint bilateral upsampling (composite.wgsl).

struct RsmParams {
    // Half-resolution target size.
    low_size: vec2<u32>,
    // VPLs per pixel and light.
    samples: u32,
    // The pass's frame counter.
    frame: u32,
    // Gather radius R in light view metres.
    radius: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> shadows: Shadows;
@group(0) @binding(2) var<uniform> params: RsmParams;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var shadow_map: texture_depth_2d_array;
@group(0) @binding(6) var rsm_normal: texture_2d_array<f32>;
@group(0) @binding(7) var rsm_flux: texture_2d_array<f32>;
@group(0) @binding(8) var indirect_out: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(9) var geometry_out: texture_storage_2d_array<rgba32float, write>;

const GOLDEN_ANGLE: f32 = 2.39996322972865;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.low_size.x || id.y >= params.low_size.y || id.z >= frame.layers) {
        return;
    }
    let layer = i32(id.z);
    let q = vec2<i32>(id.xy);
    let eye = frame.eyes[id.z];
    let f = full_res_pixel(id.xy, 2u, frame.size);
    let depth = textureLoad(depth_layers, vec2<i32>(f), layer, 0);
    if (!(depth > 0.0)) {
        textureStore(indirect_out, q, layer, vec4<f32>(0.0));
        textureStore(geometry_out, q, layer, vec4<f32>(0.0));
        return;
    }
    let position = view_position_from_depth(pixel_uv(f, frame.size), depth, eye.tangents, frame.near);
    let n = safe_normal(textureLoad(normal_layers, vec2<i32>(f), layer, 0).xyz, position);
    textureStore(geometry_out, q, layer, vec4<f32>(n, -position.z));

    let pa = anchored_from_view_point(eye, position);
    let na = anchored_from_view_vector(eye, n);
    // Per-pixel rotation (R2 sequence) and ring jitter (interleaved gradient noise), both
    // advanced each frame by irrational steps.
    let fp = vec2<f32>(id.xy);
    let turn = f32(params.frame);
    let rotation = 2.0 * PI * fract(0.5 + fp.x * 0.7548776662 + fp.y * 0.5698402910 + turn * 0.6180339887);
    let jitter = fract(52.9829189 * fract(0.06711056 * fp.x + 0.00583715 * fp.y) + turn * 0.7548776662);
    let count = max(params.samples, 1u);
    let big_r = params.radius;
    let ring = big_r / f32(count);
    var irradiance = vec3<f32>(0.0);
    for (var s = 0u; s < shadows.count; s++) {
        let light = shadows.lights[s];
        let p = light.extent.x;
        let range = light.extent.y;
        let half_side = light.extent.z;
        let size = i32(shadows.size);
        let pl = (light.view_from_anchored * vec4<f32>(pa, 1.0)).xyz;
        let nl = (light.view_from_anchored * vec4<f32>(na, 0.0)).xyz;
        for (var k = 0u; k < count; k++) {
            let r = (f32(k) + jitter) * ring;
            let angle = rotation + f32(k) * GOLDEN_ANGLE;
            let xy = pl.xy + r * vec2<f32>(cos(angle), sin(angle));
            let t = vec2<i32>(floor(vec2<f32>(xy.x + half_side, half_side - xy.y) / p));
            if (any(t < vec2<i32>(0)) || any(t >= vec2<i32>(size))) {
                continue;
            }
            let d = textureLoad(shadow_map, t, i32(s), 0);
            if (!(d < 1.0)) {
                continue; // nothing drawn there
            }
            let vpl = vec3<f32>(f32(t.x) * p + 0.5 * p - half_side, half_side - f32(t.y) * p - 0.5 * p, -d * range);
            let nq = textureLoad(rsm_normal, t, i32(s), 0).xyz;
            let flux = textureLoad(rsm_flux, t, i32(s), 0).rgb;
            let to_vpl = vpl - pl;
            let d2 = dot(to_vpl, to_vpl);
            let dir = to_vpl * inverseSqrt(max(d2, 1e-30));
            let cosines = max(dot(nl, dir), 0.0) * max(-dot(nq, dir), 0.0);
            let area = 2.0 * PI * r * big_r / f32(count);
            irradiance += flux * (cosines * area / (PI * d2 + area));
        }
    }
    textureStore(indirect_out, q, layer, vec4<f32>(finite_or_zero3(irradiance), 1.0));
}
