// The upsample pass: writes AoFull from half-resolution occlusion (joint_upsample.wgsl).
// Frames do not need it (the composite upsamples inline); debug images and tests do.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var geometry_low: texture_2d_array<f32>;
@group(0) @binding(5) var occlusion_low: texture_2d_array<f32>;
@group(0) @binding(6) var occlusion_out: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let eye = frame.eyes[id.z];
    let p = vec2<i32>(id.xy);
    let depth = textureLoad(depth_layers, p, i32(id.z), 0);
    if (depth <= 0.0) {
        textureStore(occlusion_out, p, i32(id.z), vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let position = load_view_position(depth, id.xy, eye, frame.size, frame.near);
    let n = safe_normal(textureLoad(normal_layers, p, i32(id.z), 0).xyz, position);
    textureStore(occlusion_out, p, i32(id.z), joint_upsample(geometry_low, occlusion_low, id, eye, position, n));
}
