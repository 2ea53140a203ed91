// Joint bilateral upsampling (Kopf et al. 2007; seed 000: 3×3, not separated) of
// half-resolution occlusion to full resolution. Each of the 3×3 low-res neighbours is
// weighted by its distance to the full-res pixel and by how well its geometry (normal
// and distance in AoGeometry, from the full-res pixel it was computed at) matches:
// tangent-plane distance and normal.
// Odd sizes work because low-res pixel q stands for full-res pixel min(2q, size − 1).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var geometry_low: texture_2d_array<f32>;
@group(0) @binding(5) var occlusion_low: texture_2d_array<f32>;
@group(0) @binding(6) var occlusion_out: texture_storage_2d_array<rgba16float, write>;

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
fn upsample_tap(q: vec2<i32>, id: vec3<u32>, eye: Eye, position: vec3<f32>, n: vec3<f32>, plane_scale: f32) -> Tap {
    var t: Tap;
    t.weight = 0.0;
    t.agreement = 0.0;
    if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(ao.ao_size))) {
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

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let layer = id.z;
    let eye = frame.eyes[layer];
    let p = vec2<i32>(id.xy);
    let base = vec2<i32>(id.xy / 2u);
    let nearest = textureLoad(occlusion_low, min(base, vec2<i32>(ao.ao_size) - 1), i32(layer), 0);
    let depth = textureLoad(depth_layers, p, i32(layer), 0);
    if (depth <= 0.0) {
        textureStore(occlusion_out, p, i32(layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let position = load_view_position(depth, id.xy, eye, frame.size, frame.near);
    let n = safe_normal(textureLoad(normal_layers, p, i32(layer), 0).xyz, position);
    let plane_scale = 1.0 / (PLANE_SIGMA * -position.z);
    // The 2×2 low-res samples around this pixel first; where they all agree with its
    // geometry (a smooth surface) that is the answer, else (an edge) the seed's full 3×3.
    var sum = vec4<f32>(0.0);
    var total = 0.0;
    var agree = 1.0;
    for (var i = 0; i < 4; i++) {
        let t = upsample_tap(base + vec2<i32>(i & 1, i >> 1u), id, eye, position, n, plane_scale);
        sum += t.value * t.weight;
        total += t.weight;
        agree = min(agree, t.agreement);
    }
    if (agree < EDGE_AGREEMENT) {
        for (var i = 0; i < 5; i++) {
            // (-1,-1) (0,-1) (1,-1) (-1,0) (-1,1): the rest of the 3×3.
            let offset = select(vec2<i32>(-1, i - 2), vec2<i32>(i - 1, -1), i < 3);
            let t = upsample_tap(base + offset, id, eye, position, n, plane_scale);
            sum += t.value * t.weight;
            total += t.weight;
        }
    }
    var result = nearest;
    if (total > 1e-20) {
        result = sum / total;
    }
    result = vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
    textureStore(occlusion_out, p, i32(layer), result);
}
