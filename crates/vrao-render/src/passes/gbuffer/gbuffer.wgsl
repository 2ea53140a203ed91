// G-buffer: depth, view-space normals, albedo and emission for each eye layer, and in a
// scene that moves, each pixel's motion. The vertex entry points live in
// gbuffer_multiview.wgsl (one pass, `view_index` picks the eye) or gbuffer_multipass.wgsl
// (one pass per eye, a uniform picks it).

@group(0) @binding(0) var<uniform> frame: Frame;

// The previous frame's eyes, for motion vectors (written only in a scene that moves).
struct PreviousEyes {
    clip_from_anchored: array<mat4x4<f32>, 2>,
    view_from_anchored: array<mat4x4<f32>, 2>,
};
@group(0) @binding(1) var<uniform> previous: PreviousEyes;

// Material and object bindings, `VertexIn`, `material_albedo`, `alpha_test`: shaders/mesh.wgsl.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_position: vec3<f32>,
    @location(1) view_normal: vec3<f32>,
    @location(2) uv: vec4<f32>,
    @location(3) color: vec4<f32>,
    @location(4) view_tangent: vec4<f32>,
};

// VertexOut and where the point was in the previous frame.
struct MotionVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_position: vec3<f32>,
    @location(1) view_normal: vec3<f32>,
    @location(2) uv: vec4<f32>,
    @location(3) color: vec4<f32>,
    @location(4) view_tangent: vec4<f32>,
    @location(5) previous_clip: vec4<f32>,
    // Distance along the previous view's −z.
    @location(6) previous_distance: f32,
};

fn transform_vertex(v: VertexIn, eye: u32) -> VertexOut {
    let e = frame.eyes[eye];
    let anchored = anchored_position(v);
    var out: VertexOut;
    out.clip = e.clip_from_anchored * anchored;
    out.view_position = (e.view_from_anchored * anchored).xyz;
    out.view_normal = (e.view_from_anchored * vec4<f32>(anchored_normal(v), 0.0)).xyz;
    out.uv = v.uv;
    out.color = v.color;
    let tangent = anchored_tangent(v);
    out.view_tangent = vec4<f32>((e.view_from_anchored * vec4<f32>(tangent.xyz, 0.0)).xyz, tangent.w);
    return out;
}

fn transform_vertex_with_motion(v: VertexIn, eye: u32) -> MotionVertexOut {
    let now = transform_vertex(v, eye);
    let before = previous_anchored_position(v);
    var out: MotionVertexOut;
    out.clip = now.clip;
    out.view_position = now.view_position;
    out.view_normal = now.view_normal;
    out.uv = now.uv;
    out.color = now.color;
    out.view_tangent = now.view_tangent;
    out.previous_clip = previous.clip_from_anchored[eye] * before;
    out.previous_distance = -(previous.view_from_anchored[eye] * before).z;
    return out;
}

// What a fragment writes, before it is spread over the targets a scene has.
struct Surface {
    // The surface's own normal (the AO's); w marks alpha-tested surfaces (cards: leaves,
    // grilles, fences), which GTAO takes as thin occluders (gtao.wgsl `THIN_CARDS`).
    normal: vec4<f32>,
    // Albedo; alpha carries the baked occlusion, which the composite combines with the AO.
    albedo: vec4<f32>,
    emission: vec4<f32>,
    // The normal texture's normal, for the lighting (the surface's own without one).
    shading_normal: vec4<f32>,
};

struct GBufferOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) emission: vec4<f32>,
};

struct GBufferMotionOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) emission: vec4<f32>,
    // xy: previous uv − this uv (uv: 0..1 from the top left); z: the previous distance
    // along −z minus this one; w: 1, or 0 where the point was behind the previous eye.
    @location(3) motion: vec4<f32>,
};

struct GBufferMappedOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) emission: vec4<f32>,
    @location(4) shading_normal: vec4<f32>,
};

struct GBufferMotionMappedOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) emission: vec4<f32>,
    @location(3) motion: vec4<f32>,
    @location(4) shading_normal: vec4<f32>,
};

fn shade(in: VertexOut) -> Surface {
    alpha_test(in.uv, in.color.a);
    var n = in.view_normal;
    let len2 = dot(n, n);
    // A zero or NaN interpolated normal falls back to the geometric one.
    let geometric = normalize(cross(dpdx(in.view_position), dpdy(in.view_position)));
    n = select(geometric, n * inverseSqrt(len2), len2 > 1e-20 && len2 == len2);
    // Surfaces are seen from the front: flip normals that face away from the eye, so
    // OBJ files with inconsistent winding still shade correctly. The normal texture tilts
    // the stored normal in the mesh's own frame; seen from behind, the tilted normal is
    // turned round with it (a bump on one side is a dent on the other).
    let facing = select(1.0, -1.0, dot(n, -in.view_position) < 0.0);
    let mapped = mapped_normal(n, in.view_tangent, in.view_position, in.uv) * facing;
    n = n * facing;
    let card = select(0.0, 1.0, ALPHA_TEST);
    var out: Surface;
    out.normal = vec4<f32>(finite_or_zero3(n), card);
    out.albedo = vec4<f32>(material_albedo(in.uv, in.color), material_occlusion(in.uv));
    out.emission = vec4<f32>(finite_or_zero3(material_emission(in.uv)), 0.0);
    out.shading_normal = vec4<f32>(finite_or_zero3(mapped), card);
    return out;
}

// xy: previous uv − this uv (uv: 0..1 from the top left); z: the previous distance along
// −z minus this one; w: 1, or 0 where the point was behind the previous eye.
fn motion_of(in: MotionVertexOut) -> vec4<f32> {
    let uv = in.clip.xy / vec2<f32>(frame.size);
    var motion = vec4<f32>(0.0);
    if (in.previous_clip.w > 0.0) {
        let ndc = in.previous_clip.xy / in.previous_clip.w;
        let previous_uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        motion = vec4<f32>(previous_uv - uv, in.previous_distance + in.view_position.z, 1.0);
    }
    return select(vec4<f32>(0.0), motion, all(motion == motion) && all(abs(motion) < vec4<f32>(6.0e4)));
}

fn still(in: MotionVertexOut) -> VertexOut {
    return VertexOut(in.clip, in.view_position, in.view_normal, in.uv, in.color, in.view_tangent);
}

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    let s = shade(in);
    return GBufferOut(s.normal, s.albedo, s.emission);
}

@fragment
fn fs_motion(in: MotionVertexOut) -> GBufferMotionOut {
    let s = shade(still(in));
    return GBufferMotionOut(s.normal, s.albedo, s.emission, motion_of(in));
}

@fragment
fn fs_mapped(in: VertexOut) -> GBufferMappedOut {
    let s = shade(in);
    return GBufferMappedOut(s.normal, s.albedo, s.emission, s.shading_normal);
}

@fragment
fn fs_motion_mapped(in: MotionVertexOut) -> GBufferMotionMappedOut {
    let s = shade(still(in));
    return GBufferMotionMappedOut(s.normal, s.albedo, s.emission, motion_of(in), s.shading_normal);
}
