// The light-space pass: the scene seen from one directional light through its
// orthographic fit (passes/shadow.rs). Depth always (the shadow map); with reflective
// shadow maps also each texel's normal and flux (Lin's NCTU thesis §3.3: every texel a virtual
// point light). Positions come back from the depth and the texel, so none is stored.

@group(0) @binding(0) var<uniform> light: ShadowLight;

// Material and object bindings, `VertexIn`, `material_albedo`, `alpha_test`: shaders/mesh.wgsl.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Normal in light view (+z towards the light).
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec4<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = light.clip_from_anchored * anchored_position(v);
    out.normal = (light.view_from_anchored * vec4<f32>(anchored_normal(v), 0.0)).xyz;
    out.uv = v.uv;
    out.color = v.color;
    return out;
}

struct RsmOut {
    @location(0) normal: vec4<f32>,
    @location(1) flux: vec4<f32>,
};

// Reflective shadow map texel: the normal, turned towards the light as the G-buffer
// turns normals towards the eye (surfaces are two-sided), and the flux density
// ρ · E: an orthographic texel covers p² of the light's cross-section whatever the
// surface's slope, so its flux is ρ · E · p² (the gather multiplies by the area).
// The depth-only map of alpha-tested materials: holes let the light through.
@fragment
fn fs_alpha(in: VertexOut) {
    alpha_test(in.uv, in.color.a);
}

@fragment
fn fs_rsm(in: VertexOut) -> RsmOut {
    alpha_test(in.uv, in.color.a);
    var n = in.normal;
    let len2 = dot(n, n);
    n = select(vec3<f32>(0.0, 0.0, 1.0), n * inverseSqrt(len2), len2 > 1e-20 && len2 == len2);
    if (n.z < 0.0) {
        n = -n;
    }
    let albedo = material_albedo(in.uv, in.color);
    var out: RsmOut;
    out.normal = vec4<f32>(finite_or_zero3(n), 0.0);
    out.flux = vec4<f32>(finite_or_zero3(albedo * light.radiance.rgb), 0.0);
    return out;
}
