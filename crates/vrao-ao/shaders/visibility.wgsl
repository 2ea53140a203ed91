// Bind group 1 of every compute kernel (gpu/visibility.rs): the visibility mask and the
// foveation rate as one map. `visibility_rates` holds, per tile of 8×8 full-resolution
// pixels (level 0) and of 16×16 (level 1), the share of the full sample count its pixels
// spend: 0 where the lens hides the whole tile, elsewhere the foveation rate of its point
// nearest the view axis.
// `visibility_pixels` is 1 on the pixels the lens shows and 0 on those it hides.

@group(1) @binding(0) var visibility_rates: texture_2d_array<f32>;
@group(1) @binding(1) var visibility_pixels: texture_2d_array<f32>;

// The rate of the tile of 8·`scale` full-resolution pixels holding pixel `p` of a pass that
// works at 1/`scale` of full resolution (1 or 2): every invocation of an 8×8 workgroup
// reads the same texel, so a hidden tile's early return costs one fetch per workgroup.
fn tile_rate(p: vec2<u32>, layer: u32, scale: u32) -> f32 {
    return textureLoad(visibility_rates, vec2<i32>(p / 8u), i32(layer), i32(min(scale, 2u) - 1u)).r;
}

// Whether the lens shows full-resolution pixel `p`.
fn pixel_shown(p: vec2<u32>, layer: u32) -> bool {
    return textureLoad(visibility_pixels, vec2<i32>(p), i32(layer), 0).r > 0.5;
}

// At and below this rate (the outer half of foveation's fall-off and beyond) the
// upsampling thins as the technique's sampling does (joint_upsample.wgsl
// `foveated_quad`). The denoise does not: filtering the periphery along one axis only
// raised the stereo-inconsistent points from 0.8 % to 1.8 % (docs/records/2026-11-29/summary.md).
const THIN_BELOW_RATE: f32 = 0.75;
