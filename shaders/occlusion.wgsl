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
