// Shared by the occlusion techniques (ssao, hbao, ssdo, fetch): their common bindings
// and the per-pixel set-up every technique starts with.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<storage, read> kernel: array<vec4<f32>>;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var ao_out: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(6) var geometry_out: texture_storage_2d_array<rgba32float, write>;

// The surface an occlusion pixel stands for.
struct Receiver {
    // False outside the target or on the sky (the pixel is then already written).
    valid: bool,
    layer: u32,
    eye: Eye,
    // The full-resolution G-buffer pixel behind this occlusion pixel.
    pixel: vec2<u32>,
    position: vec3<f32>,
    normal: vec3<f32>,
};

// Sets up occlusion pixel `id`: reads its depth and normal and writes its AoGeometry;
// on the sky it writes "unoccluded" and returns an invalid receiver.
fn begin_receiver(id: vec3<u32>) -> Receiver {
    var r: Receiver;
    r.valid = false;
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return r;
    }
    r.layer = id.z;
    r.eye = frame.eyes[id.z];
    r.pixel = full_res_pixel(id.xy, ao.scale, frame.size);
    let depth = textureLoad(depth_layers, vec2<i32>(r.pixel), i32(r.layer), 0);
    if (depth <= 0.0) {
        store_occlusion(id, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        textureStore(geometry_out, vec2<i32>(id.xy), i32(id.z), vec4<f32>(0.0));
        return r;
    }
    r.position = load_view_position(depth, r.pixel, r.eye, frame.size, frame.near);
    r.normal = safe_normal(textureLoad(normal_layers, vec2<i32>(r.pixel), i32(r.layer), 0).xyz, r.position);
    textureStore(geometry_out, vec2<i32>(id.xy), i32(id.z), vec4<f32>(r.normal, -r.position.z));
    r.valid = true;
    return r;
}

fn store_occlusion(id: vec3<u32>, value: vec4<f32>) {
    textureStore(ao_out, vec2<i32>(id.xy), i32(id.z), value);
}

// Whether the surface found by `probe` occludes a sample at view-space `s` for a receiver
// at `position` with normal `n`: the surface lies in front of the sample (by more than
// `bias`) AND rises above the receiver's tangent plane. The second test removes the
// self-occlusion a flat surface gives itself at grazing angles, where one pixel's depth
// spans far more than the bias.
fn occludes(probe: DepthProbe, s: vec3<f32>, position: vec3<f32>, n: vec3<f32>, eye: Eye, bias: f32) -> bool {
    if (!probe.valid || !(probe.distance < -s.z - bias)) {
        return false;
    }
    let surface = view_position_from_distance(pixel_uv(probe.pixel, frame.size), probe.distance, eye.tangents);
    return dot(surface - position, n) > bias + 1e-5 * -position.z;
}

// What the depth buffer holds where view-space point `s` projects: `valid` is false
// off-screen, behind the eye or on the sky; `distance` is the stored surface's
// distance along −z and `pixel` the full-res pixel read.
struct DepthProbe {
    valid: bool,
    pixel: vec2<u32>,
    distance: f32,
};

// The full-res pixel where view-space point `s` projects, if on screen and in front of
// the eye (`valid`; `distance` is left for the caller's fetch).
fn probe_target(s: vec3<f32>, eye: Eye) -> DepthProbe {
    var probe: DepthProbe;
    probe.valid = false;
    if (!(-s.z > frame.near * 0.5)) {
        return probe;
    }
    let uv = view_to_uv(s, eye.tangents);
    if (!(all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0)))) {
        return probe;
    }
    probe.pixel = min(vec2<u32>(uv * vec2<f32>(frame.size)), frame.size - vec2<u32>(1u));
    probe.valid = true;
    return probe;
}

fn probe_depth(depth_layers: texture_depth_2d_array, layer: u32, s: vec3<f32>, eye: Eye) -> DepthProbe {
    var probe = probe_target(s, eye);
    if (!probe.valid) {
        return probe;
    }
    let d = textureLoad(depth_layers, vec2<i32>(probe.pixel), i32(layer), 0);
    probe.valid = d > 0.0;
    probe.distance = frame.near / max(d, 1e-30);
    return probe;
}
