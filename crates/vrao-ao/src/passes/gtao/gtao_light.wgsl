// GTAO gathers no light: the hooks gtao.wgsl calls for a light-gathering march
// (passes/ssdo/ssdo.wgsl) do nothing here, and the compiler drops them.

struct GatheredLight {
    unused: f32,
};

fn begin_light(noise: f32) -> GatheredLight {
    return GatheredLight(0.0);
}

fn gather_sample(light: ptr<function, GatheredLight>, newly: u32, pixel: vec2<u32>, layer: u32, sender: vec3<f32>, p: vec3<f32>) {
}

fn end_slice(
    light: ptr<function, GatheredLight>, slice: Slice, march: March, offset: f32, projected_len: f32, weight: f32, view: vec3<f32>,
) {
}

fn light_result(light: GatheredLight, r: Receiver, visibility: f32, total: f32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn open_light(r: Receiver) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn reused_light(left: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}
