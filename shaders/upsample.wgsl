// The upsample pass: writes AoFull from half-resolution occlusion (joint_upsample.wgsl),
// one invocation per quad of 2×2 full-res pixels, i.e. per low-res sample. Frames do
// not need it (the composite upsamples inline); debug images and tests do.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var geometry_low: texture_2d_array<f32>;
@group(0) @binding(5) var occlusion_low: texture_2d_array<f32>;
@group(0) @binding(6) var occlusion_out: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x * 2u >= frame.size.x || id.y * 2u >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let eye = frame.eyes[id.z];
    let layer = i32(id.z);
    var pixels: array<UpsamplePixel, 4>;
    var sky = 0u;
    for (var k = 0u; k < 4u; k++) {
        let pixel = quad_pixel(id.xy, k);
        let depth = textureLoad(depth_layers, vec2<i32>(pixel), layer, 0);
        sky |= select(0u, 1u << k, depth <= 0.0);
        let normal = textureLoad(normal_layers, vec2<i32>(pixel), layer, 0).xyz;
        pixels[k] = upsample_pixel(pixel, eye, depth, normal);
    }
    pixels = upsample_quad(geometry_low, occlusion_low, vec2<i32>(id.xy), id.z, eye.tangents, pixels);
    for (var k = 0u; k < 4u; k++) {
        let pixel = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
        if (all(pixel < frame.size)) {
            let value = select(upsampled(pixels[k]), vec4<f32>(0.0, 0.0, 0.0, 1.0), (sky & (1u << k)) != 0u);
            textureStore(occlusion_out, vec2<i32>(pixel), layer, value);
        }
    }
}
