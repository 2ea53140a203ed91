// The host's direct light (outgoing radiance per pixel, any float format) packed with the
// view distance into the form SSDO's bounce reads (common.wgsl `pack_direct`), as vrao's
// own direct-light pass writes it.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var depth_layers: texture_depth_2d_array;
@group(0) @binding(2) var host_direct: texture_2d_array<f32>;
@group(0) @binding(3) var direct_out: texture_storage_2d_array<rg32uint, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let d = textureLoad(depth_layers, vec2<i32>(id.xy), i32(id.z), 0);
    let distance = select(0.0, frame.near / max(d, 1e-30), d > 0.0);
    // A radiance that is not finite or is negative sends nothing.
    let radiance = max(finite_or_zero3(textureLoad(host_direct, vec2<i32>(id.xy), i32(id.z), 0).rgb), vec3<f32>(0.0));
    textureStore(direct_out, vec2<i32>(id.xy), i32(id.z), pack_direct(distance, radiance));
}
