// The upsample pass: writes AoFull from half-resolution occlusion (joint_upsample.wgsl),
// one invocation per quad of 2×2 full-res pixels, i.e. per low-res sample. Frames do
// not need it (the composite upsamples inline); debug images and tests do. With the
// stereo reuse (RIGHT_EYE) the right eye runs as a dispatch of its own after the left
// (joint_upsample.wgsl `right_eye_quad`), its output bound as a one-layer view beside
// the left eye's layer. It computes the right eye's own upsample at every quad, where
// the composite does so only at the quads the left eye does not fully see (its
// FALLBACK dispatch): the values are the same, this pass costs more than with
// independent eyes (docs/records/2026-11-29/measurements-in-code.md, upsample-right-eye).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var depth_layers: texture_depth_2d_array;
@group(0) @binding(3) var normal_layers: texture_2d_array<f32>;
@group(0) @binding(4) var geometry_low: texture_2d_array<f32>;
@group(0) @binding(5) var occlusion_low: texture_2d_array<f32>;
@group(0) @binding(6) var occlusion_out: texture_storage_2d_array<rgba16float, write>;
// AoFull's left-eye layer in the right eye's dispatch (any array texture otherwise).
@group(0) @binding(7) var left_final: texture_2d_array<f32>;

override RIGHT_EYE: bool = false;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x * 2u >= frame.size.x || id.y * 2u >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    // The layer read, and the layer of the bound output written.
    let layer = select(id.z, 1u, RIGHT_EYE);
    let out_layer = select(id.z, 0u, RIGHT_EYE);
    let eye = frame.eyes[layer];
    if (tile_rate(id.xy, layer, 2u) == 0.0) {
        // A 16×16 tile the lens hides (visibility.wgsl): unoccluded, as the sky, unfetched.
        for (var k = 0u; k < 4u; k++) {
            let pixel = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
            if (all(pixel < frame.size)) {
                textureStore(occlusion_out, vec2<i32>(pixel), i32(out_layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
            }
        }
        return;
    }
    let quad = quad_pixels(depth_layers, normal_layers, id.xy, layer, eye);
    var values: array<vec4<f32>, 4>;
    if (RIGHT_EYE) {
        values = right_eye_quad(depth_layers, left_final, geometry_low, occlusion_low, quad, vec2<i32>(id.xy), eye.tangents);
    } else {
        values = upsample_quad(geometry_low, occlusion_low, quad, vec2<i32>(id.xy), layer, eye.tangents);
    }
    store(quad[0], out_layer, values[0]);
    store(quad[1], out_layer, values[1]);
    store(quad[2], out_layer, values[2]);
    store(quad[3], out_layer, values[3]);
}

// Stores a quad pixel's value (unoccluded on the sky), unless it lies past an odd edge.
fn store(px: UpsamplePixel, layer: u32, value: vec4<f32>) {
    if (all(px.pixel < frame.size)) {
        let sky = px.depth <= 0.0;
        textureStore(occlusion_out, vec2<i32>(px.pixel), i32(layer), select(value, vec4<f32>(0.0, 0.0, 0.0, 1.0), sky));
    }
}
