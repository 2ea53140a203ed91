//! Material textures on the GPU: each image with its mip chain (made here on upload:
//! 2×2 box filtered, in linear light for sRGB images), and one sampler per distinct
//! [`Sampling`] (wrap per axis, filters), shared by every material that samples that way.

use crate::scene::{Filter, Sampling, Texture, Wrap};
use std::collections::HashMap;
use vrao_ao::plug::Gpu;
use wgpu::util::DeviceExt;

/// How a texture's bytes encode its values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Colour (base colour, emission): sRGB, filtered in linear light.
    Srgb,
    /// Data (normals, occlusion): the bytes as they are.
    Linear,
}

impl Encoding {
    fn format(self) -> wgpu::TextureFormat {
        match self {
            Encoding::Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
            Encoding::Linear => wgpu::TextureFormat::Rgba8Unorm,
        }
    }
}

/// `texture` as a sampled view, with its full mip chain when its sampling uses mipmaps.
pub fn upload(gpu: &Gpu, label: &str, texture: &Texture, encoding: Encoding) -> wgpu::TextureView {
    let levels = if texture.sampling.mipmaps.is_some() {
        mip_chain(texture.width, texture.height, &texture.rgba8, encoding)
    } else {
        vec![texture.rgba8.to_vec()]
    };
    let data: Vec<u8> = levels.concat();
    let view = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: texture.width, height: texture.height, depth_or_array_layers: 1 },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: encoding.format(),
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    );
    view.create_view(&Default::default())
}

/// A 1×1 texture of one texel, bound where a material has no texture of that kind.
pub fn placeholder(gpu: &Gpu, label: &str, texel: [u8; 4], encoding: Encoding) -> wgpu::TextureView {
    let texture =
        Texture { width: 1, height: 1, rgba8: texel.to_vec().into(), source: None, sampling: Sampling::default() };
    upload(gpu, label, &texture, encoding)
}

/// The levels of a mip chain from `base` (`width × height` RGBA8) down to 1×1, each
/// level half the one above (rounded down), each texel the mean of the 2×2 texels above
/// it (a side of 1 repeats its one texel; an odd side's last texel is left out).
pub fn mip_chain(width: u32, height: u32, base: &[u8], encoding: Encoding) -> Vec<Vec<u8>> {
    let to_linear: Vec<f32> = (0..=255u8)
        .map(|b| match encoding {
            Encoding::Srgb => srgb_to_linear(b as f32 / 255.0),
            Encoding::Linear => b as f32 / 255.0,
        })
        .collect();
    let to_byte = |v: f32, colour: bool| {
        let v = if colour && encoding == Encoding::Srgb { linear_to_srgb(v) } else { v };
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    let mut levels = vec![base.to_vec()];
    let (mut w, mut h) = (width as usize, height as usize);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let above = levels.last().expect("the base level is there");
        let mut level = vec![0u8; nw * nh * 4];
        for y in 0..nh {
            for x in 0..nw {
                let xs = [2 * x, (2 * x + 1).min(w - 1)];
                let ys = [2 * y, (2 * y + 1).min(h - 1)];
                for c in 0..4 {
                    let sum: f32 = ys
                        .iter()
                        .flat_map(|&sy| xs.iter().map(move |&sx| (sy * w + sx) * 4 + c))
                        .map(|i| to_linear[above[i] as usize])
                        .sum();
                    // Alpha is linear in an sRGB format too.
                    let mean = if c == 3 && encoding == Encoding::Srgb {
                        ys.iter()
                            .flat_map(|&sy| xs.iter().map(move |&sx| above[(sy * w + sx) * 4 + 3] as f32))
                            .sum::<f32>()
                            / 4.0
                            / 255.0
                    } else {
                        sum / 4.0
                    };
                    level[(y * nw + x) * 4 + c] = to_byte(mean, c < 3);
                }
            }
        }
        levels.push(level);
        (w, h) = (nw, nh);
    }
    levels
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// One sampler per distinct way of sampling, made on first use.
#[derive(Default)]
pub struct Samplers {
    made: HashMap<(Wrap, Wrap, Filter, Filter, Option<Filter>), wgpu::Sampler>,
}

impl Samplers {
    /// The sampler for `sampling` (its transform is applied in the shader, not here).
    pub fn get(&mut self, device: &wgpu::Device, sampling: &Sampling) -> wgpu::Sampler {
        let key = (sampling.wrap_u, sampling.wrap_v, sampling.magnify, sampling.minify, sampling.mipmaps);
        self.made
            .entry(key)
            .or_insert_with(|| {
                let address = |wrap| match wrap {
                    Wrap::Repeat => wgpu::AddressMode::Repeat,
                    Wrap::MirroredRepeat => wgpu::AddressMode::MirrorRepeat,
                    Wrap::ClampToEdge => wgpu::AddressMode::ClampToEdge,
                };
                let filter = |f| match f {
                    Filter::Nearest => wgpu::FilterMode::Nearest,
                    Filter::Linear => wgpu::FilterMode::Linear,
                };
                device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("material texture"),
                    address_mode_u: address(sampling.wrap_u),
                    address_mode_v: address(sampling.wrap_v),
                    mag_filter: filter(sampling.magnify),
                    min_filter: filter(sampling.minify),
                    mipmap_filter: match sampling.mipmaps {
                        Some(Filter::Linear) => wgpu::MipmapFilterMode::Linear,
                        _ => wgpu::MipmapFilterMode::Nearest,
                    },
                    // Without mipmaps the full-size level only (the texture has one anyway).
                    lod_max_clamp: if sampling.mipmaps.is_some() { 32.0 } else { 0.0 },
                    ..Default::default()
                })
            })
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_chain_halves_to_one_texel_averaging_in_linear_light() {
        // 3×2: odd width; black and white columns.
        let (b, w) = ([0u8, 0, 0, 255], [255u8, 255, 255, 255]);
        let base: Vec<u8> = [b, w, w, b, w, w].concat();
        let srgb = mip_chain(3, 2, &base, Encoding::Srgb);
        assert_eq!(srgb.len(), 2, "3×2 then 1×1");
        assert_eq!(srgb[1].len(), 4);
        // Mean of black, white, black, white in linear light is 0.5: sRGB byte 188.
        assert_eq!(srgb[1][0], 188);
        assert_eq!(srgb[1][3], 255);
        let linear = mip_chain(3, 2, &base, Encoding::Linear);
        assert_eq!(linear[1][0], 128);
        let square = mip_chain(8, 8, &vec![7u8; 8 * 8 * 4], Encoding::Linear);
        assert_eq!(square.iter().map(Vec::len).collect::<Vec<_>>(), vec![256, 64, 16, 4]);
        assert!(square.iter().all(|l| l.iter().all(|&v| v == 7)));
    }
}
