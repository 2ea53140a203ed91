// Separable geometry-aware bilateral blur of the occlusion (the Czech SSDO thesis: 11×11, edge
// stops on normal and depth; Belonogov 2018 §4.3.2). Geometry comes from AoGeometry (normal and
// distance at each occlusion pixel, written by the technique): one fetch per tap. A neighbour
// counts by its pixel distance (Gaussian), by how far it lies off the centre's tangent plane
// relative to the centre's distance (depth edge) and by normal agreement. Each layer is blurred
// on its own; the right eye's vertical pass may instead take the left eye's result
// (denoise_stereo.wgsl). When every weight vanishes the centre value is kept.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var geometry_layers: texture_2d_array<f32>;
@group(0) @binding(3) var occlusion_in: texture_2d_array<f32>;
@group(0) @binding(4) var occlusion_out: ChainTarget;

fn blur(id: vec3<u32>, axis: vec2<i32>) {
    if (id.x >= ao.ao_size.x || id.y >= ao.ao_size.y || id.z >= frame.layers) {
        return;
    }
    let layers = denoise_layers(id);
    let layer = layers.x;
    let eye = frame.eyes[layer];
    let p = vec2<i32>(id.xy);
    if (tile_rate(id.xy, u32(layer), ao.scale) == 0.0) {
        // Hidden by the lens (visibility.wgsl): unoccluded, as the sky.
        textureStore(occlusion_out, p, layers.y, chain_texel(vec4<f32>(0.0, 0.0, 0.0, 1.0)));
        return;
    }
    let centre_value = chain_value(textureLoad(occlusion_in, p, layer, 0));
    let centre = textureLoad(geometry_layers, p, layer, 0);
    if (!(centre.w > 0.0) || ao.blur_radius == 0u) {
        textureStore(occlusion_out, p, layers.y, chain_texel(centre_value));
        return;
    }
    if (RIGHT_EYE) {
        let left = reused_from_left_eye(p, centre);
        if (left.found) {
            textureStore(occlusion_out, p, layers.y, chain_texel(left.value));
            return;
        }
    }
    let n = centre.xyz;
    let plane = tap_plane(eye, id.xy, centre, axis, ao.scale, frame.size, ao.blur_plane_sigma);
    let radius = i32(ao.blur_radius);
    let sigma = max(f32(radius) * 0.5, 0.5);
    let inv_two_sigma2 = 1.0 / (2.0 * sigma * sigma);
    var sum = vec4<f32>(0.0);
    var total = 0.0;
    for (var k = -radius; k <= radius; k++) {
        let q = p + axis * k;
        if (any(q < vec2<i32>(0)) || any(q >= vec2<i32>(ao.ao_size))) {
            continue;
        }
        let geometry = textureLoad(geometry_layers, q, layer, 0);
        if (!(geometry.w > 0.0)) {
            continue;
        }
        let kf = f32(k);
        let offset = plane_offset_of(plane, geometry.w, kf);
        // One exp for the spatial and depth terms; the normal term is (n·q)^16. Off-plane
        // offsets are NaN only for a degenerate centre: such a tap is skipped below.
        let w = exp(-kf * kf * inv_two_sigma2 - offset * offset) * normal_agreement(n, geometry.xyz);
        if (w == w) {
            sum += chain_value(textureLoad(occlusion_in, q, layer, 0)) * w;
            total += w;
        }
    }
    var result = centre_value;
    if (total > 1e-20) {
        result = sum / total;
    }
    result = vec4<f32>(finite_or_zero3(result.rgb), saturate_ao(result.a));
    textureStore(occlusion_out, p, layers.y, chain_texel(result));
}

@compute @workgroup_size(8, 8, 1)
fn blur_horizontal(@builtin(global_invocation_id) id: vec3<u32>) {
    blur(id, vec2<i32>(1, 0));
}

@compute @workgroup_size(8, 8, 1)
fn blur_vertical(@builtin(global_invocation_id) id: vec3<u32>) {
    blur(id, vec2<i32>(0, 1));
}
