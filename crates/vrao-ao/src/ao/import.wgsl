// The AO engine's front door: the host's depth (any depth format, standard or reversed,
// finite or infinite far) becomes vrao's reversed-Z infinite-far depth with the engine's
// near plane, and the host's normals (view or world space, signed or unorm-packed), or
// normals rebuilt from the depth, become view-space normals. One fullscreen triangle per
// layer; the instance index is the layer. The host's second depth layer, where two are
// read, becomes vrao's `DEPTH_LAYER_2` alike (`import_second_layer`, a depth-only pass).
// The host's textures are read through `host_depth_sample`, `host_normal_sample` and
// `host_second_sample`, which import_single.wgsl (one sample per pixel, a layered view)
// or import_msaa.wgsl (a multisampled view of the drawn layer) define.

struct ImportLayer {
    // View from world (rotation part turns world-space normals).
    view_from_world: mat4x4<f32>,
    // tan(left), tan(right), tan(up), tan(down) of the view's frustum.
    tangents: vec4<f32>,
    // distance = depth_numerator / (depth + depth_offset), from the host's projection.
    depth_offset: f32,
    depth_numerator: f32,
    padding: vec2<f32>,
};

struct ImportParams {
    layers: array<ImportLayer, 2>,
    size: vec2<u32>,
    // The engine's near plane: vrao depth = near / distance.
    near: f32,
    reversed: u32,
    // 1: the host gave normals; 0: rebuild them from the depth.
    host_normals: u32,
    unsigned_normals: u32,
    world_normals: u32,
    // The host mask's bits of pixels that cast no AO (0: no mask).
    cast_none: u32,
};

@group(0) @binding(0) var<uniform> params: ImportParams;
// The host's exclusion mask (one sample per pixel), or a placeholder of zeros.
@group(0) @binding(3) var host_mask: texture_2d_array<u32>;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) layer: u32,
};

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) layer: u32) -> VertexOut {
    let corner = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(corner * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
    out.layer = layer;
    return out;
}

// Whether `a` lies nearer the eye than `b` in the host's depth convention.
fn host_nearer(a: f32, b: f32) -> bool {
    let standard_nearer = a < b;
    let reversed_nearer = a > b;
    return select(standard_nearer, reversed_nearer, params.reversed == 1u);
}

// Distance along −z of the surface at pixel `p` (its nearest sample where the host
// multisamples), 0 for the sky (the far end of the depth range) and for anything the
// projection cannot have produced.
fn host_distance(p: vec2<i32>, layer: u32) -> f32 {
    return distance_of(host_depth_sample(p, layer).x, layer);
}

fn distance_of(depth: f32, layer: u32) -> f32 {
    let sky = select(depth >= 1.0, depth <= 0.0, params.reversed == 1u);
    let l = params.layers[layer];
    let distance = l.depth_numerator / (depth + l.depth_offset);
    let usable = !sky && distance > 0.0 && distance < 3.0e38;
    return select(0.0, distance, usable);
}

fn position_at(p: vec2<i32>, distance: f32, layer: u32) -> vec3<f32> {
    let uv = (vec2<f32>(p) + vec2<f32>(0.5)) / vec2<f32>(params.size);
    let t = params.layers[layer].tangents;
    return vec3<f32>(mix(t.x, t.y, uv.x) * distance, mix(t.z, t.w, uv.y) * distance, -distance);
}

// The step to the neighbour along `axis` (either side, whichever lies closer in depth, so
// a silhouette does not bend the normal), oriented along +axis; w = 0 when neither side
// has a surface.
fn neighbour_step(p: vec2<i32>, centre: vec3<f32>, distance: f32, axis: vec2<i32>, layer: u32) -> vec4<f32> {
    var best = vec4<f32>(0.0);
    var best_gap = 3.0e38;
    let last = vec2<i32>(params.size) - vec2<i32>(1);
    for (var side = -1; side <= 1; side += 2) {
        let q = p + axis * side;
        if (any(q < vec2<i32>(0)) || any(q > last)) {
            continue;
        }
        let d = host_distance(q, layer);
        if (d > 0.0 && abs(d - distance) < best_gap) {
            best_gap = abs(d - distance);
            best = vec4<f32>((position_at(q, d, layer) - centre) * f32(side), 1.0);
        }
    }
    return best;
}

fn rebuilt_normal(p: vec2<i32>, centre: vec3<f32>, distance: f32, layer: u32) -> vec3<f32> {
    let dx = neighbour_step(p, centre, distance, vec2<i32>(1, 0), layer);
    let dy = neighbour_step(p, centre, distance, vec2<i32>(0, 1), layer);
    // Image y runs down, view y up: dy × dx faces the eye.
    let n = cross(dy.xyz, dx.xyz);
    if (dx.w == 0.0 || dy.w == 0.0 || dot(n, n) < 1e-30) {
        return normalize(-centre);
    }
    return normalize(n);
}

fn host_normal(p: vec2<i32>, centre: vec3<f32>, layer: u32, sample: u32) -> vec3<f32> {
    var n = host_normal_sample(p, layer, sample);
    if (params.unsigned_normals == 1u) {
        n = n * 2.0 - vec3<f32>(1.0);
    }
    if (params.world_normals == 1u) {
        n = (params.layers[layer].view_from_world * vec4<f32>(n, 0.0)).xyz;
    }
    let len2 = dot(n, n);
    if (!(len2 > 1e-12 && len2 < 1e12)) {
        return normalize(-centre);
    }
    return n * inverseSqrt(len2);
}

struct ImportOut {
    @builtin(frag_depth) depth: f32,
    @location(0) normal: vec4<f32>,
};

@fragment
fn import_frame(in: VertexOut) -> ImportOut {
    let p = vec2<i32>(in.position.xy);
    let chosen = host_depth_sample(p, in.layer);
    let distance = distance_of(chosen.x, in.layer);
    var out: ImportOut;
    out.depth = 0.0;
    out.normal = vec4<f32>(0.0);
    if (distance == 0.0) {
        return out;
    }
    // A pixel that casts no AO leaves the depth the chain marches: every other pixel's
    // march and denoise see the open sky there (and it gets none itself).
    if (params.cast_none != 0u && (textureLoad(host_mask, p, i32(in.layer), 0).r & params.cast_none) != 0u) {
        return out;
    }
    let centre = position_at(p, distance, in.layer);
    var n: vec3<f32>;
    if (params.host_normals == 1u) {
        n = host_normal(p, centre, in.layer, u32(chosen.y));
    } else {
        n = rebuilt_normal(p, centre, distance, in.layer);
    }
    // Surfaces are seen from the front, as the G-buffer stores them.
    n = select(n, -n, dot(n, centre) > 0.0);
    out.depth = min(params.near / distance, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    return out;
}

// The host's second layer as vrao's: reversed-Z with the engine's near plane, read at the
// sample the first layer's resolve took; 0 (nothing behind) on the sky, where the host's
// holds its far value, and where its surface does not lie behind the first layer's (GTAO
// then keeps the thickness there).
@fragment
fn import_second_layer(in: VertexOut) -> @builtin(frag_depth) f32 {
    let p = vec2<i32>(in.position.xy);
    let chosen = host_depth_sample(p, in.layer);
    let first = distance_of(chosen.x, in.layer);
    let second = distance_of(host_second_sample(p, in.layer, u32(chosen.y)), in.layer);
    if (first == 0.0 || !(second > first)) {
        return 0.0;
    }
    // The lowest bit cleared: a host's layer does not say which face it holds, so each
    // is taken as a back face (the span to it solid; common.wgsl `second_layer_faces_eye`).
    return bitcast<f32>(bitcast<u32>(min(params.near / second, 1.0)) & ~1u);
}
