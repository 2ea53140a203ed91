// Depth peeling (Ritschel et al. 2009 §4, Everitt 2001): the second depth layer of each eye,
// the nearest surface lying behind the G-buffer's depth (the first layer). Depth only, one
// render pass per eye layer; a fragment not farther than the first layer by PEEL_GAP is
// discarded, so the depth test keeps the nearest of the rest, front or back face, and
// marks which it is where the material's winding says. On closed geometry the second
// layer is the back face of the object the first layer sees: SSDO and GTAO then count a
// sample as an occluder only between the two (inside that object). A front face there
// means the first layer is a sheet.

@group(0) @binding(0) var<uniform> frame: Frame;

// Group 1, the draw's material and object: shaders/mesh.wgsl.

struct PeelEye {
    index: u32,
    // The minimum separation behind the first layer in metres (two layers for GTAO:
    // `ao.layer_separation` × r; 0 for SSDO's peeling, which keeps PEEL_GAP alone).
    separation: f32,
};
@group(2) @binding(0) var<uniform> peel_eye: PeelEye;
@group(2) @binding(1) var first_layer: texture_depth_2d_array;

// How much farther than the first layer (as a fraction of its distance) a surface must
// be to count as the next layer: absorbs coincident duplicates and rounding between the
// two rasterisations (1 mm at 1 m), far below any thickness SSDO's bias can resolve.
override PEEL_GAP: f32 = 1e-3;

struct PeelVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec4<f32>,
    @location(1) vertex_alpha: f32,
};

// The G-buffer's transform (gbuffer.wgsl `transform_vertex`), position and uv.
@vertex
fn vs_peel(v: VertexIn) -> PeelVertexOut {
    var out: PeelVertexOut;
    out.clip = frame.eyes[peel_eye.index].clip_from_anchored * anchored_position(v);
    out.uv = v.uv;
    out.vertex_alpha = v.color.a;
    return out;
}

// The fragment's depth, its lowest bit saying whether the surface faces the eye
// (common.wgsl `second_layer_with_facing`). Only a single-sided material's winding says
// which face is which (its culling relies on it); OBJ windings are not trusted, so a
// double-sided material's faces count as back faces, the span to them solid.
fn peeled_depth(in: PeelVertexOut, faces_eye: bool) -> f32 {
    alpha_test(in.uv, in.vertex_alpha);
    let p = in.clip;
    // Reversed Z with an infinite far plane: distance = near / depth, so "farther than
    // the first layer by the gap" is depth × (1 + gap) < first depth. On the sky (first
    // depth 0) nothing is behind.
    let first = textureLoad(first_layer, vec2<i32>(p.xy), i32(peel_eye.index), 0);
    if (!(p.z * (1.0 + PEEL_GAP) < first)) {
        discard;
    }
    // At least `separation` farther: distance near / z > near / first + separation.
    if (peel_eye.separation > 0.0 && !(p.z * (frame.near / first + peel_eye.separation) < frame.near)) {
        discard;
    }
    return second_layer_with_facing(p.z, faces_eye);
}

@fragment
fn fs_peel(in: PeelVertexOut) -> @builtin(frag_depth) f32 {
    return peeled_depth(in, false);
}

@fragment
fn fs_peel_single_sided(in: PeelVertexOut, @builtin(front_facing) front_facing: bool) -> @builtin(frag_depth) f32 {
    return peeled_depth(in, front_facing);
}
