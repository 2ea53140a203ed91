// The import pass's reads of a multisampled host: views of the drawn layer of its depth,
// normals and second depth layer (the bind group is the layer's, so `layer` is not needed
// to read them).
//
// The resolve rule: a pixel takes its sample nearest the eye, and the normal and second
// layer of that same sample. Where a silhouette crosses the pixel the foreground wins, as it does in the
// host's resolved colour wherever the foreground covers most of the pixel; an average of
// depths would invent a surface floating between the two (docs/engine.md).

@group(0) @binding(1) var host_depth: texture_depth_multisampled_2d;
@group(0) @binding(2) var host_normals: texture_multisampled_2d<f32>;
@group(0) @binding(4) var host_second_depth: texture_depth_multisampled_2d;

fn host_depth_sample(p: vec2<i32>, layer: u32) -> vec2<f32> {
    var best = textureLoad(host_depth, p, 0);
    var best_sample = 0u;
    for (var s = 1u; s < textureNumSamples(host_depth); s += 1u) {
        let depth = textureLoad(host_depth, p, i32(s));
        if (host_nearer(depth, best)) {
            best = depth;
            best_sample = s;
        }
    }
    return vec2<f32>(best, f32(best_sample));
}

fn host_normal_sample(p: vec2<i32>, layer: u32, sample: u32) -> vec3<f32> {
    return textureLoad(host_normals, p, i32(sample)).xyz;
}

fn host_second_sample(p: vec2<i32>, layer: u32, sample: u32) -> f32 {
    return textureLoad(host_second_depth, p, i32(sample));
}
