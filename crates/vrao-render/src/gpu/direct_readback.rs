//! Reading the renderer's direct light back: its packed texels (rg32uint, the engine's
//! common.wgsl `pack_direct`) as radiance.

/// The `Direct` resource's packed texels (rg32uint, common.wgsl `pack_direct`) as rgba
/// f32 values per layer: the RGB9E5 radiance, and 0 in alpha (the packed distance is the
/// bounce's business only).
pub fn decode_direct(raw: Vec<Vec<u8>>) -> Vec<Vec<f32>> {
    raw.into_iter()
        .map(|bytes| {
            bytes
                .chunks_exact(8)
                .flat_map(|t| {
                    let [r, g, b] = unpack_rgb9e5(u32::from_le_bytes([t[4], t[5], t[6], t[7]]));
                    [r, g, b, 0.0]
                })
                .collect()
        })
        .collect()
}

/// The shared-exponent RGB9E5 form of common.wgsl `pack_rgb9e5`: three 9-bit mantissas
/// and a 5-bit exponent biased by 15.
pub fn unpack_rgb9e5(bits: u32) -> [f32; 3] {
    let scale = 2f32.powi((bits >> 27) as i32 - 24);
    [bits & 511, (bits >> 9) & 511, (bits >> 18) & 511].map(|m| m as f32 * scale)
}

#[cfg(test)]
mod tests {
    use super::unpack_rgb9e5;

    #[test]
    fn rgb9e5_decodes_the_shared_exponent_form() {
        let texel = |m: [u32; 3], exponent: u32| m[0] | (m[1] << 9) | (m[2] << 18) | (exponent << 27);
        // 1.0 is mantissa 256 at exponent 16 (2^(16 − 15 − 9) = 1/256).
        assert_eq!(unpack_rgb9e5(texel([256, 128, 0], 16)), [1.0, 0.5, 0.0]);
        // The largest value, 511 × 2^7, and the smallest step, 2^-24.
        assert_eq!(unpack_rgb9e5(texel([511, 0, 1], 31)), [65408.0, 0.0, 128.0]);
        assert_eq!(unpack_rgb9e5(texel([0, 1, 0], 0)), [0.0, 2f32.powi(-24), 0.0]);
    }
}
