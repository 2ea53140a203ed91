// What every pass that draws the scene's meshes shares (the G-buffer, the light-space
// pass, the depth peel): the draw's bind group (group 1, `GpuScene`'s `material_layout`:
// material, diffuse texture, sampler, object transforms), the vertex layout (`Vertex`,
// raster.rs `MESH_ATTRIBUTES`), the object transform, the material's albedo and the
// alpha test.

struct Material {
    diffuse: vec4<f32>,   // rgb linear; w = 1 when a texture modulates it
    emission: vec4<f32>,
    alpha: vec4<f32>,     // x: alpha factor; y: alpha-test cutoff (< 0: solid)
};
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var diffuse_texture: texture_2d<f32>;
@group(1) @binding(2) var diffuse_sampler: sampler;

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
    @location(2) uv: vec2<f32>,
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

// The material's albedo at `uv`, in 0..1. Call it in uniform control flow, every
// fragment (untextured materials bind a white texel): sampling inside a branch made
// lavapipe 22.3 leak memory at every draw (docs/measurements-in-code.md, mesh-albedo-leak).
fn material_albedo(uv: vec2<f32>) -> vec3<f32> {
    let texel = textureSample(diffuse_texture, diffuse_sampler, uv).rgb;
    let albedo = material.diffuse.rgb * select(vec3<f32>(1.0), texel, material.diffuse.w > 0.5);
    return clamp(albedo, vec3<f32>(0.0), vec3<f32>(1.0));
}

// Discards the fragment where the material's alpha is below its cutoff: a hole in every
// pass that draws the mesh. The sample is taken unconditionally (see material_albedo).
fn alpha_test(uv: vec2<f32>) {
    let alpha = material.alpha.x * textureSample(diffuse_texture, diffuse_sampler, uv).a;
    if (ALPHA_TEST && alpha < material.alpha.y) {
        discard;
    }
}
