// The import pass's reads of a host that gives one sample per pixel: layered views of its
// depth, normals and second depth layer (the layer is the view).

@group(0) @binding(1) var host_depth: texture_depth_2d_array;
@group(0) @binding(2) var host_normals: texture_2d_array<f32>;
@group(0) @binding(4) var host_second_depth: texture_depth_2d_array;

// The pixel's depth in x, and in y the sample it came from (always 0 here).
fn host_depth_sample(p: vec2<i32>, layer: u32) -> vec2<f32> {
    return vec2<f32>(textureLoad(host_depth, p, i32(layer), 0), 0.0);
}

fn host_normal_sample(p: vec2<i32>, layer: u32, sample: u32) -> vec3<f32> {
    return textureLoad(host_normals, p, i32(layer), 0).xyz;
}

fn host_second_sample(p: vec2<i32>, layer: u32, sample: u32) -> f32 {
    return textureLoad(host_second_depth, p, i32(layer), 0);
}
