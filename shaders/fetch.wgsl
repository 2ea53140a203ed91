// Benchmark baseline, not an occlusion technique: the same number of depth taps as SSAO,
// spread over the same screen footprint, with almost no arithmetic. A technique's time
// divided by this one's says how far it is from the memory (texture fetch) limit.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<storage, read> kernel: array<vec4<f32>>;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var ao_out: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(6) var geometry_out: texture_storage_2d_array<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return;
    }
    let layer = i32(id.z);
    let fp = vec2<i32>(full_res_pixel(id.xy, ao.scale, frame.size));
    let depth = textureLoad(depth_layers, fp, layer, 0);
    // The geometry the blur and upsample read, as every technique writes it.
    let n = textureLoad(normal_layers, fp, layer, 0).xyz;
    textureStore(geometry_out, vec2<i32>(id.xy), layer, vec4<f32>(n, select(0.0, frame.near / depth, depth > 0.0)));
    // The footprint of the radius in pixels, as SSAO's samples cover it.
    let eye = frame.eyes[id.z];
    let radius_px = ao.radius * depth / frame.near * f32(frame.size.x) / (eye.tangents.y - eye.tangents.x);
    let limit = vec2<i32>(frame.size) - vec2<i32>(1);
    var sum = 0.0;
    for (var i = 0u; i < ao.samples; i++) {
        let k = kernel[i];
        let q = clamp(fp + vec2<i32>(k.xy * (k.w * radius_px)), vec2<i32>(0), limit);
        sum += textureLoad(depth_layers, q, layer, 0);
    }
    // Depths are never negative: this keeps the taps alive without changing the result.
    textureStore(ao_out, vec2<i32>(id.xy), layer, vec4<f32>(0.0, 0.0, 0.0, select(1.0, 0.0, sum < -1.0)));
}
