// What every pass that draws the scene's meshes shares (the G-buffer, the light-space
// pass, the depth peel): the draw's bind group (group 1, `GpuScene`'s `material_layout`:
// material, its four textures with their samplers, object transforms), the vertex layout (`Vertex`,
// raster.rs `MESH_ATTRIBUTES`), the object transform, the material's albedo and the
// alpha test.

struct Material {
    diffuse: vec4<f32>,   // rgb linear; w = 1 when a texture modulates it
    emission: vec4<f32>,  // rgb linear radiance, times the emissive texture
    // x: alpha factor; y: alpha-test cutoff (< 0: solid); z: normal texture scale (0:
    // none); w: occlusion texture strength (0: none).
    alpha: vec4<f32>,
    // Each texture's placement (KHR_texture_transform), two rows per texture in the
    // order below: (the 2×2 matrix's columns), (the offset, the uv set it reads, 0).
    placements: array<vec4<f32>, 8>,
};
const DIFFUSE: u32 = 0u;
const EMISSIVE: u32 = 1u;
const NORMAL: u32 = 2u;
const OCCLUSION: u32 = 3u;

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var diffuse_texture: texture_2d<f32>;
@group(1) @binding(2) var diffuse_sampler: sampler;
@group(1) @binding(4) var emissive_texture: texture_2d<f32>;
@group(1) @binding(5) var emissive_sampler: sampler;
@group(1) @binding(6) var normal_texture: texture_2d<f32>;
@group(1) @binding(7) var normal_sampler: sampler;
@group(1) @binding(8) var occlusion_texture: texture_2d<f32>;
@group(1) @binding(9) var occlusion_sampler: sampler;

// The draw's object: identity for static geometry (already anchored), the node's
// transform for a moving mesh, with the previous frame's for motion vectors.
struct Object {
    anchored_from_local: mat4x4<f32>,
    previous_anchored_from_local: mat4x4<f32>,
    normal_from_local: mat4x4<f32>,
};
@group(1) @binding(3) var<uniform> object: Object;

struct VertexIn {
    @location(0) position: vec3<f32>,   // anchored (static) or the object's local frame
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec4<f32>,         // xy: set 0 (TEXCOORD_0), zw: set 1 (TEXCOORD_1)
    @location(3) color: vec4<f32>,      // linear RGBA, white without vertex colours
    @location(4) tangent: vec4<f32>,    // xyz along +u, w the bitangent's sign; 0 without
};

// Set by the pipelines that draw the alpha-tested materials (and only those).
override ALPHA_TEST: bool = false;

fn anchored_position(v: VertexIn) -> vec4<f32> {
    return object.anchored_from_local * vec4<f32>(v.position, 1.0);
}

fn previous_anchored_position(v: VertexIn) -> vec4<f32> {
    return object.previous_anchored_from_local * vec4<f32>(v.position, 1.0);
}

fn anchored_normal(v: VertexIn) -> vec3<f32> {
    return (object.normal_from_local * vec4<f32>(v.normal, 0.0)).xyz;
}

// The tangent moves with the surface (the object's transform, not the normals' one).
fn anchored_tangent(v: VertexIn) -> vec4<f32> {
    return vec4<f32>((object.anchored_from_local * vec4<f32>(v.tangent.xyz, 0.0)).xyz, v.tangent.w);
}

// Where texture `k` reads the mesh's texture coordinates `uvs` (sets 0 and 1 in xy, zw):
// the set it names, placed.
fn placed(k: u32, uvs: vec4<f32>) -> vec2<f32> {
    let m = material.placements[2u * k];
    let row = material.placements[2u * k + 1u];
    let uv = select(uvs.xy, uvs.zw, row.z > 0.5);
    return m.xy * uv.x + m.zw * uv.y + row.xy;
}

// The material's albedo at `uv` times the vertex colour, in 0..1. Call it in uniform
// control flow, every fragment (untextured materials bind a white texel): sampling inside
// a branch made lavapipe 22.3 leak memory at every draw
// (docs/records/2026-11-29/measurements-in-code.md, mesh-albedo-leak).
fn material_albedo(uv: vec4<f32>, color: vec4<f32>) -> vec3<f32> {
    let texel = textureSample(diffuse_texture, diffuse_sampler, placed(DIFFUSE, uv)).rgb;
    let albedo = material.diffuse.rgb * select(vec3<f32>(1.0), texel, material.diffuse.w > 0.5) * color.rgb;
    return clamp(albedo, vec3<f32>(0.0), vec3<f32>(1.0));
}

// Emitted radiance at `uv` (the factor times the emissive texture, white without one).
fn material_emission(uv: vec4<f32>) -> vec3<f32> {
    return material.emission.rgb * textureSample(emissive_texture, emissive_sampler, placed(EMISSIVE, uv)).rgb;
}

// Baked occlusion at `uv`: 1 + strength × (texel − 1), 1 without an occlusion texture.
fn material_occlusion(uv: vec4<f32>) -> f32 {
    let texel = textureSample(occlusion_texture, occlusion_sampler, placed(OCCLUSION, uv)).r;
    return clamp(1.0 + material.alpha.w * (texel - 1.0), 0.0, 1.0);
}

// The normal texture's normal at `uv` around the unit normal `n` (view space, seen from
// the front), with the surface's `tangent` (view space, w the bitangent's sign) or, where
// the mesh has none (zero), the tangent frame found from the position's and the
// coordinates' screen-space derivatives (as the glTF sample viewer does). `n` itself
// without a normal texture (scale 0).
fn mapped_normal(n: vec3<f32>, tangent: vec4<f32>, view_position: vec3<f32>, uv: vec4<f32>) -> vec3<f32> {
    let at = placed(NORMAL, uv);
    let texel = textureSample(normal_texture, normal_sampler, at).xyz * 2.0 - 1.0;
    let scale = material.alpha.z;
    // The derived frame, found in uniform control flow (derivatives need it).
    let dp_dx = dpdx(view_position);
    let dp_dy = dpdy(view_position);
    let duv_dx = dpdx(at);
    let duv_dy = dpdy(at);
    let det = sign_or_one(duv_dx.x * duv_dy.y - duv_dy.x * duv_dx.y);
    let along_u = (duv_dy.y * dp_dx - duv_dx.y * dp_dy) * det;
    // ∂p/∂v tells mirrored coordinates: glTF's +y (image up) is −v.
    let along_v = (duv_dx.x * dp_dy - duv_dy.x * dp_dx) * det;
    let derived_sign = select(1.0, -1.0, dot(cross(n, along_u), along_v) > 0.0);
    let has_tangent = dot(tangent.xyz, tangent.xyz) >= 1e-12;
    var t = select(along_u, tangent.xyz, has_tangent);
    let sign = select(derived_sign, sign_or_one(tangent.w), has_tangent);
    t = t - n * dot(n, t);
    let t_len2 = dot(t, t);
    let mapped = vec3<f32>(texel.xy * scale, texel.z);
    let frame_ok = t_len2 > 1e-20 && t_len2 == t_len2 && scale != 0.0;
    let tu = t * inverseSqrt(max(t_len2, 1e-30));
    let b = cross(n, tu) * sign;
    let out = tu * mapped.x + b * mapped.y + n * mapped.z;
    let out_len2 = dot(out, out);
    return select(n, out * inverseSqrt(out_len2), frame_ok && out_len2 > 1e-20 && out_len2 == out_len2);
}

fn sign_or_one(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

// Discards the fragment where the material's alpha (times the vertex colour's) is below
// its cutoff: a hole in every pass that draws the mesh. The sample is taken
// unconditionally (see material_albedo).
fn alpha_test(uv: vec4<f32>, vertex_alpha: f32) {
    let alpha = material.alpha.x * vertex_alpha * textureSample(diffuse_texture, diffuse_sampler, placed(DIFFUSE, uv)).a;
    if (ALPHA_TEST && alpha < material.alpha.y) {
        discard;
    }
}
