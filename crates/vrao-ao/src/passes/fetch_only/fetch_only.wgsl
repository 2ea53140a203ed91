// Benchmark baseline, not an occlusion technique: the same number of depth taps as SSAO,
// spread over the same screen footprint, with almost no arithmetic. A technique's time
// divided by this one's says how far it is from the memory (texture fetch) limit.

// Bindings and `begin_receiver` (the per-pixel set-up every technique pays too):
// occlusion.wgsl.

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let r = begin_receiver(id);
    if (!r.valid) {
        return;
    }
    let layer = i32(r.layer);
    let fp = vec2<i32>(r.pixel);
    // The footprint of the radius in pixels, as SSAO's samples cover it.
    let radius_px = ao.radius / -r.position.z * f32(frame.size.x) / (r.eye.tangents.y - r.eye.tangents.x);
    let limit = vec2<i32>(frame.size) - vec2<i32>(1);
    var sum = 0.0;
    for (var i = 0u; i < ao.samples; i++) {
        let k = kernel[i];
        let q = clamp(fp + vec2<i32>(k.xy * (k.w * radius_px)), vec2<i32>(0), limit);
        sum += textureLoad(depth_layers, q, layer, 0);
    }
    // Depths are never negative: this keeps the taps alive without changing the result.
    store_occlusion(id, vec4<f32>(0.0, 0.0, 0.0, select(1.0, 0.0, sum < -1.0)));
}
