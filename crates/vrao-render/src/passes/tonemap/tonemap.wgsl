// Reinhard's global operator with a white point (the Czech SSDO thesis, eq. 2.4) on luminance,
// then sRGB encoding. Exposure is the same for both eyes so they never disagree.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var hdr_layers: texture_2d_array<f32>;
@group(0) @binding(2) var color_out: texture_storage_2d_array<rgba8unorm, write>;
@group(0) @binding(3) var<uniform> shading: Shading;

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= frame.size.x || id.y >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let hdr = max(finite_or_zero3(textureLoad(hdr_layers, p, i32(id.z), 0).rgb), vec3<f32>(0.0));
    let scaled = hdr * shading.exposure;
    let l = luminance(scaled);
    let white2 = shading.white_point * shading.white_point;
    // L_d = L (1 + L / L_white²) / (1 + L); colour keeps its chromaticity.
    let ld = l * (1.0 + l / white2) / (1.0 + l);
    var ldr = vec3<f32>(0.0);
    if (l > 1e-12) {
        ldr = scaled * (ld / l);
    }
    let encoded = srgb_encode(clamp(ldr, vec3<f32>(0.0), vec3<f32>(1.0)));
    textureStore(color_out, p, i32(id.z), vec4<f32>(encoded, 1.0));
}
