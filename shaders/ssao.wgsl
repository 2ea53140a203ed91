// SSAO (seed 003 §3.2, seed 000 ch. 3): N points in a normal-oriented hemisphere around
// each pixel's view-space position, most of them close to it; a point is occluded when
// the depth buffer holds a surface in front of it. Applied to the ambient term only.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var<storage, read> kernel: array<vec4<f32>>;
@group(0) @binding(3) var depth_layers: texture_depth_2d_array;
@group(0) @binding(4) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(5) var ao_out: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(6) var geometry_out: texture_storage_2d_array<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return;
    }
    let layer = id.z;
    let eye = frame.eyes[layer];
    let fp = full_res_pixel(id.xy, ao.scale, frame.size);
    let depth = textureLoad(depth_layers, vec2<i32>(fp), i32(layer), 0);
    if (depth <= 0.0) {
        textureStore(ao_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
        textureStore(geometry_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(0.0));
        return;
    }
    let position = load_view_position(depth, fp, eye, frame.size, frame.near);
    let n = safe_normal(textureLoad(normal_layers, vec2<i32>(fp), i32(layer), 0).xyz, position);
    textureStore(geometry_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(n, -position.z));
    let frame_rot = tangent_frame(n, kernel_rotation(fp, ao.noise));
    let bias = ao.bias * ao.radius;
    let origin = position + n * bias;
    var occlusion = 0.0;
    for (var i = 0u; i < ao.samples; i++) {
        let k = kernel[i];
        let s = origin + frame_rot * k.xyz * (k.w * ao.radius);
        let probe = probe_depth(depth_layers, layer, s, eye);
        if (occludes(probe, s, position, n, eye, bias)) {
            var weight = 1.0;
            if (ao.range_check != 0u) {
                // Depth constraint: occluders far in front of the pixel (a foreground
                // object, not a neighbour) fade out instead of casting a halo.
                weight = smoothstep(0.0, 1.0, ao.radius / max(abs(-position.z - probe.distance), 1e-20));
            }
            occlusion += weight;
        }
    }
    let visibility = 1.0 - occlusion / f32(max(ao.samples, 1u));
    let result = saturate_ao(1.0 - ao.strength * (1.0 - visibility));
    textureStore(ao_out, vec2<i32>(id.xy), i32(layer), vec4<f32>(0.0, 0.0, 0.0, result));
}
