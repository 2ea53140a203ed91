// What every pass that draws the scene's meshes with their materials shares (the
// G-buffer, the light-space pass): the material bind group (group 1, `GpuScene`'s
// `material_layout`), the vertex layout (`Vertex`, raster.rs `MESH_ATTRIBUTES`) and the
// material's albedo.

struct Material {
    diffuse: vec4<f32>,   // rgb linear; w = 1 when a texture modulates it
    emission: vec4<f32>,
};
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var diffuse_texture: texture_2d<f32>;
@group(1) @binding(2) var diffuse_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,   // relative to the scene anchor
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

// The material's albedo at `uv`, in 0..1. Call it in uniform control flow, every
// fragment (untextured materials bind a white texel): sampling inside a branch made
// lavapipe 22.3 leak ~0.4 MB per draw.
fn material_albedo(uv: vec2<f32>) -> vec3<f32> {
    let texel = textureSample(diffuse_texture, diffuse_sampler, uv).rgb;
    let albedo = material.diffuse.rgb * select(vec3<f32>(1.0), texel, material.diffuse.w > 0.5);
    return clamp(albedo, vec3<f32>(0.0), vec3<f32>(1.0));
}
