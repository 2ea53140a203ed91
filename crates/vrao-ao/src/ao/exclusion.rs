//! What a host leaves out of the AO: a per-pixel mask (its own integer texture, or the
//! stencil of its depth-stencil buffer) whose bits mark pixels that receive no AO (their
//! AO is 1: UI panels, a HUD) and pixels that cast none (hands, controllers: they leave
//! the depth the chain marches, so nothing behind them darkens; they get no AO
//! themselves either). The import pass applies the casting bits, the output pass the
//! receiving ones; without a mask neither reads anything and the AO is unchanged.

use super::AoConfig;
use crate::error::{Error, Result};
use crate::gpu::Gpu;

/// A host's exclusion mask for one frame ([`super::AoFrame::exclusion`]).
#[derive(Clone, Copy, Debug)]
pub struct HostExclusion<'a> {
    /// One layer per view at the engine's size, one sample per pixel, `TEXTURE_BINDING`:
    /// an `R8Uint`, `R16Uint` or `R32Uint` texture, or a depth-stencil texture
    /// (`Depth24PlusStencil8`, `Depth32FloatStencil8`, `Stencil8`) whose stencil is read.
    pub texture: &'a wgpu::Texture,
    /// The mask bits of pixels that receive no AO (their AO is 1); 0 for none.
    pub receive_none: u32,
    /// The mask bits of pixels that cast no AO onto others; 0 for none.
    pub cast_none: u32,
}

/// The mask's binding in the import and output passes: one sample per pixel, a layer per
/// view, read as unsigned integers.
pub(crate) const MASK_BINDING: wgpu::BindingType = wgpu::BindingType::Texture {
    sample_type: wgpu::TextureSampleType::Uint,
    view_dimension: wgpu::TextureViewDimension::D2Array,
    multisampled: false,
};

const STENCIL_FORMATS: [wgpu::TextureFormat; 3] = [
    wgpu::TextureFormat::Depth24PlusStencil8,
    wgpu::TextureFormat::Depth32FloatStencil8,
    wgpu::TextureFormat::Stencil8,
];
const UINT_FORMATS: [wgpu::TextureFormat; 3] =
    [wgpu::TextureFormat::R8Uint, wgpu::TextureFormat::R16Uint, wgpu::TextureFormat::R32Uint];

/// The mask checked against the engine's configuration, as the view both passes bind
/// (its stencil aspect for a depth-stencil texture); the error names what is wrong.
pub(crate) fn mask_view(exclusion: &HostExclusion, config: &AoConfig) -> Result<wgpu::TextureView> {
    let texture = exclusion.texture;
    super::host_texture::check_texture("exclusion mask", texture, config)?;
    let format = texture.format();
    let aspect = if STENCIL_FORMATS.contains(&format) {
        wgpu::TextureAspect::StencilOnly
    } else if UINT_FORMATS.contains(&format) {
        wgpu::TextureAspect::All
    } else {
        return Err(Error::input(format!(
            "exclusion mask: format {format:?} is neither one of {UINT_FORMATS:?} nor one with stencil {STENCIL_FORMATS:?}"
        )));
    };
    if exclusion.receive_none == 0 && exclusion.cast_none == 0 {
        return Err(Error::input("exclusion mask: receive_none and cast_none are both 0 (no bit marks anything)"));
    }
    Ok(texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("exclusion mask"),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        aspect,
        base_array_layer: 0,
        array_layer_count: Some(config.views),
        ..Default::default()
    }))
}

/// What the passes bind without a mask: two layers of zeros (read only when a mask's
/// bits are set, which they are not then).
pub(crate) fn placeholder(gpu: &Gpu) -> wgpu::TextureView {
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("no exclusion mask"),
        size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 2 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R8Uint,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}
