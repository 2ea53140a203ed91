// Composite: direct light plus the ambient term attenuated by occlusion, in HDR. With
// HALF_RES the occlusion arrives at half resolution and is upsampled here, instead of in
// a pass of its own; so is the RSM bounce. One invocation shades a quad of 2×2 pixels
// (joint_upsample.wgsl `upsample_quad`: each low-res sample fetched once per quad);
// without upsampling this costs what one pixel per invocation does (docs/records/2026-11-29/summary.md).
// `ao.technique` is the technique table's composite mode: COMPOSITE_UNOCCLUDED, the
// unoccluded ambient (SH irradiance of the environment); COMPOSITE_SCALAR_AO, ambient × AO
// (GTAO, SSAO, HBAO); COMPOSITE_DIRECTIONAL, SSDO's gathered irradiance (rgb) replaces it.
// Sky pixels show the environment. The output's alpha holds the pixel's AO.
//
// With the stereo reuse at half resolution (AO-only techniques) the left eye is
// composited first, then the right eye (RIGHT_EYE) takes the left eye's AO from the
// output's alpha wherever the left eye sees the same point (joint_upsample.wgsl
// `left_eye_quad`); its output is bound as a one-layer view beside a sampled view of
// the left eye's layer. A right-eye quad with any pixel the left eye does not see (the
// outer side, disocclusions: a small share) is listed with the pixels it shaded, and a
// second, indirect dispatch (FALLBACK) over exactly those quads upsamples their own
// occlusion and shades the rest. Done in one dispatch, every quad paid for both on
// lavapipe, which runs an untaken branch anyway
// (docs/records/2026-11-29/measurements-in-code.md, composite-fallback), and on a GPU
// every warp holding one such quad would.

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
// irradiance and its geometry at half resolution, upsampled like the occlusion (RSM only).
@group(0) @binding(11) var rsm_indirect: texture_2d_array<f32>;
@group(0) @binding(12) var rsm_geometry: texture_2d_array<f32>;
// The output's left-eye layer in the right eye's dispatch (any array texture otherwise).
@group(0) @binding(13) var left_hdr: texture_2d_array<f32>;

// The AO the left eye's composite left in its colour's alpha for the right eye
// (joint_upsample.wgsl `left_eye_quad`).
fn left_final_ao(texel: vec4<f32>) -> f32 {
    return texel.a;
}

// The same for the 2×2 texels a gather at `corner` fetches (layer 0).
fn left_final_gather_ao(t: texture_2d_array<f32>, s: sampler, corner: vec2<f32>) -> vec4<f32> {
    return textureGather(3, t, s, corner, 0);
}

// The lighting's normals (the normal texture's where a material has one; `normal_layers`
// are the surface's own, which the upsampling weighs by).
@group(0) @binding(15) var lighting_normal_layers: texture_2d_array<f32>;
// The nearest sampler the right eye gathers the left eye's 2×2 blocks through.
@group(0) @binding(16) var gather: sampler;

override HALF_RES: bool = false;
// A pipeline constant, not a uniform: lavapipe pays for the upsample code even when a
// uniform skips it (docs/records/2026-11-29/measurements-in-code.md, composite-constant).
override RSM: bool = false;
override RIGHT_EYE: bool = false;
// The right eye's second dispatch, over the listed quads (implies RIGHT_EYE).
override FALLBACK: bool = false;

// The right-eye quads the left eye does not fully see, and the indirect dispatch's
// workgroup counts over them (x grows by one per 64 quads listed; y = z = 1).
struct FallbackQuads {
    groups_x: atomic<u32>,
    groups_y: u32,
    groups_z: u32,
    count: atomic<u32>,
    // Quad b and the pixels already shaded (joint_upsample.wgsl `pack_quad`).
    quads: array<u32>,
};
@group(0) @binding(14) var<storage, read_write> fallback: FallbackQuads;

// Outgoing radiance at `pixel`, whose stored depth and normal are `depth` and `n`: the
// environment on the sky; else the direct light plus albedo/π × the ambient, which
// `occlusion` attenuates (technique 1) or replaces (technique 2, SSDO's irradiance),
// plus the RSM `bounce`.
fn shade(pixel: vec2<u32>, layer: u32, eye: Eye, depth: f32, n: vec3<f32>, occlusion: vec4<f32>, bounce: vec3<f32>) -> vec3<f32> {
    let p = vec2<i32>(pixel);
    if (depth <= 0.0) {
        if (frame.has_environment == 0u) {
            return vec3<f32>(0.0);
        }
        let dir = (eye.world_from_view * vec4<f32>(view_ray(pixel_uv(pixel, frame.size), eye.tangents), 0.0)).xyz;
        return environment_radiance(environment, environment_sampler, dir);
    }
    let surface = textureLoad(albedo_layers, p, i32(layer), 0);
    let albedo = surface.rgb;
    // The material's baked occlusion (1 without an occlusion texture). Baked and
    // screen-space AO estimate the same visibility, so the smaller one holds: multiplying
    // would darken twice where both see the same crease.
    let baked = surface.a;
    var ambient = vec3<f32>(0.0);
    if (frame.has_environment != 0u) {
        ambient = environment_irradiance(layer, n);
    }
    if (ao.technique == COMPOSITE_SCALAR_AO) {
        ambient *= min(saturate_ao(occlusion.a), baked);
    } else if (ao.technique == COMPOSITE_DIRECTIONAL) {
        // SSDO's irradiance already holds its visibility (a): the baked one lowers it
        // only where it is smaller.
        let visibility = saturate_ao(occlusion.a);
        ambient = max(occlusion.rgb, vec3<f32>(0.0)) * select(1.0, baked / visibility, baked < visibility);
    } else {
        ambient *= baked;
    }
    return direct_radiance(textureLoad(direct_layers, p, i32(layer), 0)) + albedo / PI * (ambient + bounce);
}

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    var b = id.xy;
    // The pixels of the quad that this dispatch leaves as they are (bit k for pixel k).
    var keep = 0u;
    if (FALLBACK) {
        let i = group.x * 64u + local;
        if (i >= atomicLoad(&fallback.count)) {
            return;
        }
        let listed = unpack_quad(fallback.quads[i]);
        b = listed.xy;
        keep = listed.z;
    } else if (id.x * 2u >= frame.size.x || id.y * 2u >= frame.size.y || id.z >= frame.layers) {
        return;
    }
    // The layer read, and the layer of the bound output written.
    let layer = select(id.z, 1u, RIGHT_EYE);
    let out_layer = select(id.z, 0u, RIGHT_EYE);
    let eye = frame.eyes[layer];
    if (tile_rate(b, layer, 2u) == 0.0) {
        // A 16×16 tile the lens hides (visibility.wgsl): black, unfetched.
        for (var k = 0u; k < 4u; k++) {
            let pixel = b * 2u + vec2<u32>(k & 1u, k >> 1u);
            if (all(pixel < frame.size)) {
                textureStore(hdr_out, vec2<i32>(pixel), i32(out_layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
            }
        }
        return;
    }
    // The quad's depths and normals, for the joint bilateral weights and the shading.
    // Its arrays are indexed by constants only (joint_upsample.wgsl says why).
    let quad = quad_pixels(depth_layers, normal_layers, b, layer, eye);
    let unoccluded = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    var occlusion = array<vec4<f32>, 4>(unoccluded, unoccluded, unoccluded, unoccluded);
    var bounce = array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    if (ao.technique != COMPOSITE_UNOCCLUDED) {
        if (HALF_RES && RIGHT_EYE && !FALLBACK) {
            let left = left_eye_quad(depth_layers, left_hdr, gather, quad);
            occlusion = left.values;
            if (!all(left.found)) {
                // Shaded here where the left eye gives the AO, by the fallback elsewhere.
                let i = atomicAdd(&fallback.count, 1u);
                fallback.quads[i] = pack_quad(b, left.found);
                if (i % 64u == 0u) {
                    atomicAdd(&fallback.groups_x, 1u);
                }
                keep = quad_bits(!left.found);
            }
        } else if (HALF_RES) {
            // Either eye's own upsample (the right eye's FALLBACK: of the pixels the left
            // eye does not see).
            occlusion = upsample_quad(geometry_low, occlusion_layers, quad, vec2<i32>(b), layer, eye.tangents, true);
        } else {
            occlusion = array<vec4<f32>, 4>(
                full_res_occlusion(quad[0], layer),
                full_res_occlusion(quad[1], layer),
                full_res_occlusion(quad[2], layer),
                full_res_occlusion(quad[3], layer),
            );
        }
    }
    if (RSM) {
        let up = upsample_quad(rsm_geometry, rsm_indirect, quad, vec2<i32>(b), layer, eye.tangents, false);
        let none = vec3<f32>(0.0);
        bounce = array<vec3<f32>, 4>(max(up[0].rgb, none), max(up[1].rgb, none), max(up[2].rgb, none), max(up[3].rgb, none));
    }
    if ((keep & 1u) == 0u) {
        shade_and_store(quad[0], layer, out_layer, eye, occlusion[0], bounce[0]);
    }
    if ((keep & 2u) == 0u) {
        shade_and_store(quad[1], layer, out_layer, eye, occlusion[1], bounce[1]);
    }
    if ((keep & 4u) == 0u) {
        shade_and_store(quad[2], layer, out_layer, eye, occlusion[2], bounce[2]);
    }
    if ((keep & 8u) == 0u) {
        shade_and_store(quad[3], layer, out_layer, eye, occlusion[3], bounce[3]);
    }
}

// The full-resolution occlusion at a quad pixel.
fn full_res_occlusion(px: UpsamplePixel, layer: u32) -> vec4<f32> {
    return chain_value(textureLoad(occlusion_layers, vec2<i32>(px.texel), i32(layer), 0));
}

// Shades a quad pixel of `layer` and stores it (with its AO) at `out_layer` of the
// bound output, unless it lies past an odd edge.
fn shade_and_store(px: UpsamplePixel, layer: u32, out_layer: u32, eye: Eye, occlusion: vec4<f32>, bounce: vec3<f32>) {
    if (all(px.pixel < frame.size)) {
        // The G-buffer leaves the lens's hidden pixels as sky in depth: black, not sky.
        if (px.depth <= 0.0 && !pixel_shown(px.pixel, layer)) {
            textureStore(hdr_out, vec2<i32>(px.pixel), i32(out_layer), vec4<f32>(0.0, 0.0, 0.0, 1.0));
            return;
        }
        let n = textureLoad(lighting_normal_layers, vec2<i32>(px.pixel), i32(layer), 0).xyz;
        let radiance = shade(px.pixel, layer, eye, px.depth, n, occlusion, bounce);
        let stored = vec4<f32>(finite_or_zero3(radiance), saturate_ao(occlusion.a));
        textureStore(hdr_out, vec2<i32>(px.pixel), i32(out_layer), stored);
    }
}
