// Lighting and composite: direct diffuse light from the scene's lights plus the
// environment's irradiance (ambient), in HDR. Sky pixels show the environment.
// This is where occlusion plugs in: the ambient term is what AO attenuates.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var albedo_layers: texture_2d_array<f32>;
@group(0) @binding(5) var emission_layers: texture_2d_array<f32>;
@group(0) @binding(6) var environment: texture_2d<f32>;
@group(0) @binding(7) var environment_sampler: sampler;
@group(0) @binding(8) var hdr_out: texture_storage_2d_array<rgba16float, write>;

// Irradiance from the order-2 SH projection (Ramamoorthi & Hanrahan 2001), world normal.
fn sh_irradiance(n: vec3<f32>) -> vec3<f32> {
    let c = frame.irradiance_sh;
    var e = c[0].xyz * 0.282095;
    e += c[1].xyz * (0.488603 * n.y) + c[2].xyz * (0.488603 * n.z) + c[3].xyz * (0.488603 * n.x);
    e += c[4].xyz * (1.092548 * n.x * n.y) + c[5].xyz * (1.092548 * n.y * n.z);
    e += c[6].xyz * (0.315392 * (3.0 * n.z * n.z - 1.0));
    e += c[7].xyz * (1.092548 * n.x * n.z) + c[8].xyz * (0.546274 * (n.x * n.x - n.y * n.y));
    return max(e, vec3<f32>(0.0));
}

// Equirectangular lookup; the layout matches `scene::Environment::direction`.
fn environment_radiance(dir: vec3<f32>) -> vec3<f32> {
    let d = normalize(dir);
    let u = fract(atan2(d.x, -d.z) / (2.0 * PI) + 0.5);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return textureSampleLevel(environment, environment_sampler, vec2<f32>(u, v), 0.0).rgb;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let layer = id.z;
    let eye = frame.eyes[layer];
    let p = vec2<i32>(id.xy);
    let uv = pixel_uv(id.xy, frame.size);
    let depth = textureLoad(depth_layers, p, i32(layer), 0);
    var radiance = vec3<f32>(0.0);
    if (depth <= 0.0) {
        // Nothing was drawn: the sky at infinity.
        if (frame.has_environment != 0u) {
            let dir = (eye.world_from_view * vec4<f32>(view_ray(uv, eye.tangents), 0.0)).xyz;
            radiance = environment_radiance(dir);
        }
    } else {
        let position = view_position_from_depth(uv, depth, eye.tangents, frame.near);
        let n = textureLoad(normal_layers, p, i32(layer), 0).xyz;
        let albedo = textureLoad(albedo_layers, p, i32(layer), 0).rgb;
        var irradiance = vec3<f32>(0.0);
        for (var i = 0u; i < frame.light_count; i++) {
            let light = lights[layer * frame.light_count + i];
            if (light.kind.x == 0u) {
                irradiance += light.radiance.rgb * max(dot(n, -light.pos_or_dir.xyz), 0.0);
            } else {
                let to_light = light.pos_or_dir.xyz - position;
                // Clamp the distance so a light on a surface does not blow up to Inf.
                let d2 = max(dot(to_light, to_light), 1e-4);
                irradiance += light.radiance.rgb * max(dot(n, to_light * inverseSqrt(d2)), 0.0) / d2;
            }
        }
        if (frame.has_environment != 0u) {
            let world_n = (eye.world_from_view * vec4<f32>(n, 0.0)).xyz;
            irradiance += sh_irradiance(world_n);
        }
        let emission = textureLoad(emission_layers, p, i32(layer), 0).rgb;
        radiance = albedo / PI * irradiance + emission;
    }
    textureStore(hdr_out, p, i32(layer), vec4<f32>(finite_or_zero3(radiance), 1.0));
}
