// Reprojection of a finished stereo frame to a newer head pose (the simulated
// compositor's late warp). Two modes:
// - rotational: every pixel is treated as infinitely far, so only the change of
//   orientation matters (a homography per eye);
// - depth-based (positional): the source frame's depth is forward-splatted into the
//   target view with an atomic depth test (nearest wins), then each target pixel is
//   back-projected with that depth and samples the source colour. Pixels no source
//   pixel reached (disocclusions) take the farthest depth in their neighbourhood, i.e.
//   the background, so the hole is filled from what was behind the occluder.
// Sky pixels (depth 0) are rotational in both modes: they are at infinity.

struct Reproject {
    // Per layer: maps target view-space points into the source eye's view space, and back.
    source_from_target: array<mat4x4<f32>, 2>,
    target_from_source: array<mat4x4<f32>, 2>,
    source_tangents: array<vec4<f32>, 2>,
    target_tangents: array<vec4<f32>, 2>,
    size: vec2<u32>,
    layers: u32,
    near: f32,
};

@group(0) @binding(0) var<uniform> warp: Reproject;
@group(0) @binding(1) var source_depth: texture_depth_2d_array;
@group(0) @binding(2) var source_color: texture_2d_array<f32>;
@group(0) @binding(3) var color_sampler: sampler;
// Target depth per pixel and layer: the bits of a reversed-Z depth (positive floats
// order as unsigned integers; larger = nearer), 0 = nothing landed here.
@group(0) @binding(4) var<storage, read_write> splatted: array<atomic<u32>>;
@group(0) @binding(5) var color_out: texture_storage_2d_array<rgba8unorm, write>;

override POSITIONAL: bool = true;

// A usable reversed-Z depth: in (0, 1]. 0 is the sky; NaN, Inf, negatives or values past
// the near plane (a corrupted history) count as no depth at all.
fn valid_depth(d: f32) -> bool {
    return d > 0.0 && d <= 1.0;
}

fn splat_index(p: vec2<i32>, layer: u32) -> u32 {
    return (layer * warp.size.y + u32(p.y)) * warp.size.x + u32(p.x);
}

// Forward pass: each source pixel with geometry lands in the target view; its depth is
// written to the 2×2 target pixels around where it lands, nearest wins. The 2×2
// footprint closes the cracks of a surface that the move magnifies (up to 2×).
@compute @workgroup_size(8, 8, 1)
fn splat(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= warp.size.x || id.y >= warp.size.y || id.z >= warp.layers) {
        return;
    }
    let depth = textureLoad(source_depth, vec2<i32>(id.xy), i32(id.z), 0);
    if (!valid_depth(depth)) {
        return;
    }
    let in_source = view_position_from_depth(pixel_uv(id.xy, warp.size), depth, warp.source_tangents[id.z], warp.near);
    let in_target = (warp.target_from_source[id.z] * vec4<f32>(in_source, 1.0)).xyz;
    if (!(-in_target.z > warp.near)) {
        return;
    }
    let moved_depth = warp.near / -in_target.z;
    let at = view_to_uv(in_target, warp.target_tangents[id.z]) * vec2<f32>(warp.size) - vec2<f32>(0.5);
    if (!(all(at > vec2<f32>(-1.0)) && all(at < vec2<f32>(warp.size)))) {
        return;
    }
    let base = vec2<i32>(floor(at));
    for (var k = 0; k < 4; k++) {
        let p = base + vec2<i32>(k & 1, k >> 1u);
        if (all(p >= vec2<i32>(0)) && all(p < vec2<i32>(warp.size))) {
            atomicMax(&splatted[splat_index(p, id.z)], bitcast<u32>(moved_depth));
        }
    }
}

// Where the source frame shows the target pixel's direction if it were infinitely far.
fn rotational_uv(uv: vec2<f32>, layer: u32) -> vec2<f32> {
    // w = 0: only the rotation acts.
    let dir = (warp.source_from_target[layer] * vec4<f32>(view_ray(uv, warp.target_tangents[layer]), 0.0)).xyz;
    if (!(-dir.z > 0.0)) {
        return vec2<f32>(-1.0);
    }
    return view_to_uv(dir, warp.source_tangents[layer]);
}

// The target pixel's depth: what landed on it; else 0 when the source saw sky in that
// direction (the pixel is sky); else the farthest of what landed within two pixels (a
// disocclusion, filled with the background beside it).
fn target_depth(p: vec2<i32>, layer: u32) -> f32 {
    let own = atomicLoad(&splatted[splat_index(p, layer)]);
    if (own != 0u) {
        return bitcast<f32>(own);
    }
    let at_infinity = rotational_uv(pixel_uv(vec2<u32>(p), warp.size), layer);
    if (all(at_infinity >= vec2<f32>(0.0)) && all(at_infinity < vec2<f32>(1.0))) {
        let q = min(vec2<u32>(at_infinity * vec2<f32>(warp.size)), warp.size - vec2<u32>(1u));
        if (!valid_depth(textureLoad(source_depth, vec2<i32>(q), i32(layer), 0))) {
            return 0.0;
        }
    }
    var farthest = 0u;
    for (var dy = -2; dy <= 2; dy++) {
        for (var dx = -2; dx <= 2; dx++) {
            let q = p + vec2<i32>(dx, dy);
            if (all(q >= vec2<i32>(0)) && all(q < vec2<i32>(warp.size))) {
                let d = atomicLoad(&splatted[splat_index(q, layer)]);
                if (d != 0u && (farthest == 0u || d < farthest)) {
                    farthest = d;
                }
            }
        }
    }
    return bitcast<f32>(farthest);
}

@compute @workgroup_size(8, 8, 1)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= warp.size.x || id.y >= warp.size.y || id.z >= warp.layers) {
        return;
    }
    let uv = pixel_uv(id.xy, warp.size);
    var depth = 0.0;
    if (POSITIONAL) {
        depth = target_depth(vec2<i32>(id.xy), id.z);
    }
    var source_uv: vec2<f32>;
    var visible = true;
    if (depth > 0.0) {
        let in_target = view_position_from_depth(uv, depth, warp.target_tangents[id.z], warp.near);
        let in_source = (warp.source_from_target[id.z] * vec4<f32>(in_target, 1.0)).xyz;
        visible = -in_source.z > 0.0;
        source_uv = view_to_uv(in_source, warp.source_tangents[id.z]);
    } else {
        source_uv = rotational_uv(uv, id.z);
        visible = all(source_uv != vec2<f32>(-1.0));
    }
    var color = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    if (visible && all(source_uv == source_uv)) {
        // Outside the source frame the sampler clamps to its edge (the usual compositor
        // behaviour: stretched edge pixels rather than black).
        color = textureSampleLevel(source_color, color_sampler, clamp(source_uv, vec2<f32>(0.0), vec2<f32>(1.0)), i32(id.z), 0.0);
    }
    textureStore(color_out, vec2<i32>(id.xy), i32(id.z), vec4<f32>(color.rgb, 1.0));
}
