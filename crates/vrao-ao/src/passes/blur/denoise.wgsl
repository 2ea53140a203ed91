// The default denoise: an edge-aware box over GTAO's 4×4 interleaved noise tile, split
// into a horizontal and a vertical pass of 5 taps each, weighted ½, 1, 1, 1, ½. Offsets
// −2 and +2 hold the same noise pattern (4 apart), so each pass gives each of the
// tile's 4 columns (rows) the same total weight, and the window is centred: no
// half-pixel shift. Each invocation filters a run of 4 pixels along the axis, so
// a pixel costs 2 fetched taps per pass (4 in all, its own included) and 10 plane tests of two
// multiply-adds, against the 11×11 bilateral blur's 22 fetched taps with an exp and a
// normal test each. Only SSDO's targets carry light in rgb (CARRIES_LIGHT); for the other
// techniques the filter runs on alpha alone, a quarter of the arithmetic.
//
// A tap counts by how far it lies off the pixel's tangent plane, relative to the
// pixel's distance (a tent, no exp): depth edges stay sharp. Where a pixel's neighbours
// are almost all rejected (a lone pixel, a thin feature), the plain mean of its window
// is blended in, so no isolated extreme value survives untouched. With two views the
// right eye's vertical pass takes the left eye's result where the left eye sees the same
// point (denoise_stereo.wgsl).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: AoParams;
@group(0) @binding(2) var geometry_layers: texture_2d_array<f32>;
@group(0) @binding(3) var occlusion_in: texture_2d_array<f32>;
@group(0) @binding(4) var occlusion_out: ChainTarget;

// Pixels filtered by one invocation, consecutive along the pass's axis: their windows
// overlap, so 4 + 4 taps serve 4 pixels (2 taps per pixel instead of 5).
const RUN: i32 = 4;

// Whether the occlusion carries gathered light in rgb (SSDO) to filter with the AO; the
// other techniques write rgb 0, kept as is.
override CARRIES_LIGHT: bool = true;

fn denoise(id: vec3<u32>, axis: vec2<i32>) {
    let first = vec2<i32>(id.xy) * (vec2<i32>(1) + axis * (RUN - 1));
    if (any(first >= vec2<i32>(ao.ao_size)) || id.z >= frame.layers) {
        return;
    }
    let layers = denoise_layers(id);
    let layer = layers.x;
    let eye = frame.eyes[layer];
    let limit = vec2<i32>(ao.ao_size) - vec2<i32>(1);
    // A run lies in one 8×8 tile of the visibility map: where the lens hides it, the run
    // is written as the sky is (unoccluded) and loads nothing.
    if (tile_rate(vec2<u32>(first), u32(layer), ao.scale) == 0.0) {
        for (var o = 0; o < RUN; o++) {
            let p = first + axis * o;
            if (all(p <= limit)) {
                textureStore(occlusion_out, p, layers.y, chain_texel(vec4<f32>(0.0, 0.0, 0.0, 1.0)));
            }
        }
        return;
    }
    // The right eye's pixels the left eye sees (bit o for pixel o of the run, also set
    // past the edge): written here, skipped below; a run of only those loads no taps.
    var reused = 0u;
    if (RIGHT_EYE) {
        for (var o = 0; o < RUN; o++) {
            let p = first + axis * o;
            if (any(p > limit)) {
                reused |= 1u << u32(o);
                continue;
            }
            let centre = textureLoad(geometry_layers, p, layer, 0);
            if (centre.w > 0.0) {
                let left = reused_from_left_eye(p, centre);
                if (left.found) {
                    textureStore(occlusion_out, p, layers.y, chain_texel(left.value));
                    reused |= 1u << u32(o);
                }
            }
        }
        if (reused == (1u << u32(RUN)) - 1u) {
            return;
        }
    }
    // The run's taps, offsets −2 … RUN + 1 from its first pixel; clamped at the border
    // (the edge texel stands in for the missing ones).
    var geometry: array<vec4<f32>, 8>;
    var occlusion: array<f32, 8>;
    var light: array<vec3<f32>, 8>;
    for (var j = 0; j < RUN + 4; j++) {
        let q = clamp(first + axis * (j - 2), vec2<i32>(0), limit);
        geometry[j] = textureLoad(geometry_layers, q, layer, 0);
        let value = chain_value(textureLoad(occlusion_in, q, layer, 0));
        occlusion[j] = value.a;
        light[j] = select(vec3<f32>(0.0), value.rgb, CARRIES_LIGHT);
    }
    for (var o = 0; o < RUN; o++) {
        let p = first + axis * o;
        if (any(p > limit)) {
            break;
        }
        if (((reused >> u32(o)) & 1u) != 0u) {
            continue;
        }
        let centre = geometry[o + 2];
        if (!(centre.w > 0.0)) {
            // Sky: passed through.
            textureStore(occlusion_out, p, layers.y, chain_texel(vec4<f32>(light[o + 2], occlusion[o + 2])));
            continue;
        }
        let plane = tap_plane(eye, vec2<u32>(p), centre, axis, ao.scale, frame.size, ao.blur_plane_sigma);
        var sum = 0.0;
        var light_sum = vec3<f32>(0.0);
        var total = 0.0;
        var plain_sum = 0.0;
        var light_total = 0.0;
        var plain_total = 0.0;
        for (var k = -2; k <= 2; k++) {
            let distance = geometry[o + k + 2].w;
            let box = select(1.0, 0.5, abs(k) == 2);
            let on_surface = select(0.0, box, distance > 0.0);
            let w = on_surface * max(1.0 - abs(plane_offset_of(plane, distance, f32(k))), 0.0);
            sum += occlusion[o + k + 2] * w;
            total += w;
            plain_sum += occlusion[o + k + 2] * on_surface;
            plain_total += on_surface;
            if (CARRIES_LIGHT) {
                // The light also stops at normal edges: the irradiance changes with the
                // normal (a crease's floor and wall see different skies) where the AO
                // need not. The centre weighs 1, so the total never vanishes.
                let wl = w * normal_agreement(centre.xyz, geometry[o + k + 2].xyz);
                light_sum += light[o + k + 2] * wl;
                light_total += wl;
            }
        }
        // The centre alone weighs 1; below 2 the window's plain mean makes up the rest.
        let prior = max(2.0 - total, 0.0);
        let plain_weight = prior / max(plain_total, 1e-20);
        let normaliser = 1.0 / max(total + prior, 1e-20);
        let result = (sum + plain_sum * plain_weight) * normaliser;
        var light_result = vec3<f32>(0.0);
        if (CARRIES_LIGHT) {
            light_result = finite_or_zero3(light_sum / max(light_total, 1e-20));
        }
        textureStore(occlusion_out, p, layers.y, chain_texel(vec4<f32>(light_result, saturate_ao(result))));
    }
}

@compute @workgroup_size(8, 8, 1)
fn denoise_horizontal(@builtin(global_invocation_id) id: vec3<u32>) {
    denoise(id, vec2<i32>(1, 0));
}

@compute @workgroup_size(8, 8, 1)
fn denoise_vertical(@builtin(global_invocation_id) id: vec3<u32>) {
    denoise(id, vec2<i32>(0, 1));
}
