// Composite: direct light plus the ambient term attenuated by occlusion, in HDR. With
// HALF_RES the occlusion arrives at half resolution and is upsampled here, per pixel
// (joint_upsample.wgsl), instead of in a pass of its own.
// technique 0: unoccluded ambient (SH irradiance of the environment);
// 1: ambient × AO (SSAO, HBAO); 2: SSDO's gathered irradiance (rgb) replaces it.
// Sky pixels show the environment.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var albedo_layers: texture_2d_array<f32>;
@group(0) @binding(5) var direct_layers: texture_2d_array<u32>;
@group(0) @binding(6) var occlusion_layers: texture_2d_array<f32>;
@group(0) @binding(7) var environment: texture_2d<f32>;
@group(0) @binding(8) var environment_sampler: sampler;
@group(0) @binding(9) var hdr_out: texture_storage_2d_array<rgba16float, write>;
// AoGeometry of half-resolution occlusion (HALF_RES only).
@group(0) @binding(10) var geometry_low: texture_2d_array<f32>;
// One bounce of the directional lights from reflective shadow maps (rsm.wgsl): the
// irradiance and its geometry at half resolution, upsampled in rsm_upsample.wgsl (RSM only).
@group(0) @binding(11) var rsm_indirect: texture_2d_array<f32>;
@group(0) @binding(12) var rsm_geometry: texture_2d_array<f32>;

override HALF_RES: bool = false;
// A pipeline constant, not a uniform: lavapipe pays for the upsample code even when a
// uniform skips it (composite 122 → 213 ms at 1080×1200 on Sibenik).
override RSM: bool = false;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let layer = i32(id.z);
    let eye = frame.eyes[id.z];
    let p = vec2<i32>(id.xy);
    let depth = textureLoad(depth_layers, p, layer, 0);
    var radiance = vec3<f32>(0.0);
    if (depth <= 0.0) {
        if (frame.has_environment != 0u) {
            let dir = (eye.world_from_view * vec4<f32>(view_ray(pixel_uv(id.xy, frame.size), eye.tangents), 0.0)).xyz;
            radiance = environment_radiance(environment, environment_sampler, dir);
        }
    } else {
        let n = textureLoad(normal_layers, p, layer, 0).xyz;
        let albedo = textureLoad(albedo_layers, p, layer, 0).rgb;
        var ambient = vec3<f32>(0.0);
        if (frame.has_environment != 0u) {
            ambient = environment_irradiance(id.z, n);
        }
        var occlusion = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        if (ao.technique != 0u) {
            if (HALF_RES) {
                let position = view_position_from_depth(pixel_uv(id.xy, frame.size), depth, eye.tangents, frame.near);
                occlusion = joint_upsample(geometry_low, occlusion_layers, id, eye, position, safe_normal(n, position));
            } else {
                occlusion = textureLoad(occlusion_layers, p, layer, 0);
            }
        }
        if (ao.technique == 1u) {
            ambient *= saturate_ao(occlusion.a);
        } else if (ao.technique == 2u) {
            ambient = max(occlusion.rgb, vec3<f32>(0.0));
        }
        if (RSM) {
            let position = view_position_from_depth(pixel_uv(id.xy, frame.size), depth, eye.tangents, frame.near);
            ambient += rsm_upsample(rsm_geometry, rsm_indirect, id, eye, position, safe_normal(n, position));
        }
        radiance = direct_radiance(textureLoad(direct_layers, p, layer, 0)) + albedo / PI * ambient;
    }
    textureStore(hdr_out, p, layer, vec4<f32>(finite_or_zero3(radiance), 1.0));
}
