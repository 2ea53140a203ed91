// G-buffer: depth, view-space normals, albedo and emission for each eye layer.
// The vertex entry point lives in gbuffer_multiview.wgsl (one pass, `view_index` picks
// the eye) or gbuffer_multipass.wgsl (one pass per eye, a uniform picks it).

@group(0) @binding(0) var<uniform> frame: Frame;

// Material bindings, `VertexIn` and `material_albedo`: shaders/mesh.wgsl.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_position: vec3<f32>,
    @location(1) view_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

fn transform_vertex(v: VertexIn, eye: u32) -> VertexOut {
    let e = frame.eyes[eye];
    var out: VertexOut;
    out.clip = e.clip_from_anchored * vec4<f32>(v.position, 1.0);
    out.view_position = (e.view_from_anchored * vec4<f32>(v.position, 1.0)).xyz;
    out.view_normal = (e.view_from_anchored * vec4<f32>(v.normal, 0.0)).xyz;
    out.uv = v.uv;
    return out;
}

struct GBufferOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) emission: vec4<f32>,
};

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    var n = in.view_normal;
    let len2 = dot(n, n);
    // A zero or NaN interpolated normal falls back to the geometric one.
    let geometric = normalize(cross(dpdx(in.view_position), dpdy(in.view_position)));
    n = select(geometric, n * inverseSqrt(len2), len2 > 1e-20 && len2 == len2);
    // Surfaces are seen from the front: flip normals that face away from the eye, so
    // OBJ files with inconsistent winding still shade correctly.
    if (dot(n, -in.view_position) < 0.0) {
        n = -n;
    }
    let albedo = material_albedo(in.uv);
    var out: GBufferOut;
    out.normal = vec4<f32>(finite_or_zero3(n), 0.0);
    out.albedo = vec4<f32>(albedo, 1.0);
    out.emission = vec4<f32>(finite_or_zero3(material.emission.rgb), 0.0);
    return out;
}
