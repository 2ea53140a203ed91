// Direct light: the scene's point, spot and directional lights on diffuse surfaces, plus
// emission, as outgoing radiance. The composite adds the ambient term on top, and
// SSDO's bounce uses this as the sender radiance L_pixel (Ritschel et al. 2009 eq. 2); the view
// distance rides along (`pack_direct`) so that the bounce's occluder probe reads
// distance and sender radiance in one fetch.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
// The lighting's normals (the normal texture's where a material has one).
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var albedo_layers: texture_2d_array<f32>;
@group(0) @binding(5) var emission_layers: texture_2d_array<f32>;
@group(0) @binding(6) var direct_out: texture_storage_2d_array<rg32uint, write>;
// Shadow maps of the directional lights (shadow.wgsl); `shadows.count` is 0 when off.
@group(0) @binding(7) var<uniform> shadows: Shadows;
@group(0) @binding(8) var shadow_map: texture_depth_2d_array;
@group(0) @binding(9) var shadow_sampler: sampler_comparison;
@group(0) @binding(10) var<uniform> shading: Shading;

// Fraction of directional light `i` reaching view-space `position` (normal `n`) of `eye`:
// its shadow map's 3×3 PCF when it has one, else 1.
fn directional_visibility(i: u32, eye: Eye, position: vec3<f32>, n: vec3<f32>) -> f32 {
    for (var s = 0u; s < shadows.count; s++) {
        if (shadows.lights[s].index.x == i) {
            let pa = anchored_from_view_point(eye, position);
            let na = anchored_from_view_vector(eye, n);
            return pcf_visibility(shadow_map, shadow_sampler, shadows.lights[s], s, shadows.size, pa, na);
        }
    }
    return 1.0;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let layer = id.z;
    let eye = frame.eyes[layer];
    let p = vec2<i32>(id.xy);
    // A tile the lens hides (visibility.wgsl) lights nothing: read as the sky, unfetched.
    var depth = 0.0;
    if (tile_rate(id.xy, layer, 1u) > 0.0) {
        depth = textureLoad(depth_layers, p, i32(layer), 0);
    }
    var radiance = vec3<f32>(0.0);
    var n = vec3<f32>(0.0, 0.0, 1.0);
    var distance = 0.0;
    if (depth > 0.0) {
        distance = frame.near / max(depth, 1e-30);
        let position = view_position_from_depth(pixel_uv(id.xy, frame.size), depth, eye.tangents, frame.near);
        n = textureLoad(normal_layers, p, i32(layer), 0).xyz;
        let albedo = textureLoad(albedo_layers, p, i32(layer), 0).rgb;
        var irradiance = vec3<f32>(0.0);
        for (var i = 0u; i < shading.light_count; i++) {
            let light = lights[layer * shading.light_count + i];
            if (light.kind.x == 0u) {
                let cos_l = max(dot(n, -light.pos_or_dir.xyz), 0.0);
                if (cos_l > 0.0) {
                    irradiance += light.radiance.rgb * cos_l * directional_visibility(i, eye, position, n);
                }
            } else {
                let to_light = light.pos_or_dir.xyz - position;
                // Clamp the distance so a light on a surface does not blow up to Inf.
                let d2 = max(dot(to_light, to_light), 1e-4);
                let l = to_light * inverseSqrt(d2);
                var falloff = 1.0;
                if (light.kind.x == 2u) {
                    // glTF's spot falloff: the square of a ramp in the cosine off the axis.
                    let ramp = clamp((dot(light.spot_direction.xyz, -l) - light.cone.x) * light.cone.y, 0.0, 1.0);
                    falloff = ramp * ramp;
                }
                irradiance += light.radiance.rgb * falloff * max(dot(n, l), 0.0) / d2;
            }
        }
        let emission = textureLoad(emission_layers, p, i32(layer), 0).rgb;
        radiance = albedo / PI * irradiance + emission;
    }
    textureStore(direct_out, p, i32(layer), pack_direct(distance, finite_or_zero3(radiance)));
}
