//! The visibility mask and foveation map on the GPU ([`crate::visibility`]): bind group 1 of
//! every compute kernel (`shaders/visibility.wgsl`) holds each view's rate map (two levels:
//! 8×8 and 16×16 pixel tiles) and its per-pixel coverage. Both are remade and uploaded only
//! when what they follow changes (size, fields of view, mask, foveation, `mask` setting),
//! not every frame.

use super::Gpu;
use crate::frame::ChainSettings;
use crate::stereo::Eye;
use crate::visibility::{RateMap, VisibilityMask};

/// The layout of bind group 1: the rate map (two mip levels) and the per-pixel coverage,
/// both `texture_2d_array<f32>` read with `textureLoad`.
pub(crate) fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("visibility"),
        entries: &[entry(0), entry(1)],
    })
}

/// What the per-pixel coverage follows.
#[derive(Clone, PartialEq)]
struct CoverageKey {
    width: u32,
    height: u32,
    tangents: Vec<[u64; 4]>,
    mask: Option<VisibilityMask>,
}

/// What the rate map follows besides the coverage.
#[derive(Clone, PartialEq)]
struct RateKey {
    coverage: CoverageKey,
    foveation: crate::settings::Foveation,
}

/// The textures of bind group 1 and what they were made for.
pub struct VisibilityMaps {
    tiles: wgpu::Texture,
    pixels: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    coverage: Vec<Option<Vec<u8>>>,
    coverage_key: Option<CoverageKey>,
    rate_key: Option<RateKey>,
    hidden_share: Vec<f64>,
}

impl VisibilityMaps {
    /// Maps of one 16×16 view, every pixel shown, until the first [`VisibilityMaps::update`].
    pub fn new(gpu: &Gpu) -> VisibilityMaps {
        let (tiles, pixels) = textures(gpu, 16, 16, 1, 2, 2);
        let group = bind_group(gpu, &tiles, &pixels);
        let maps = VisibilityMaps {
            tiles,
            pixels,
            bind_group: group,
            coverage: Vec::new(),
            coverage_key: None,
            rate_key: None,
            hidden_share: Vec::new(),
        };
        let all = vec![255u8; 16 * 16];
        upload(gpu, &maps.pixels, 0, 0, (16, 16), &all);
        upload(gpu, &maps.tiles, 0, 0, (2, 2), &all[..4]);
        upload(gpu, &maps.tiles, 0, 1, (1, 1), &all[..1]);
        maps
    }

    /// Bind group 1 of every compute kernel.
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// The per-pixel coverage texture (255 shown, 0 hidden), one layer per view.
    pub fn coverage_texture(&self) -> &wgpu::Texture {
        &self.pixels
    }

    /// Whether a mask hides any pixel this frame.
    pub fn masked(&self) -> bool {
        self.coverage.iter().any(Option::is_some)
    }

    /// The share of each view's pixels the mask hides this frame (0 without one).
    pub fn hidden_share(&self) -> &[f64] {
        &self.hidden_share
    }

    /// Each view's coverage this frame (`None`: every pixel shown), row by row.
    pub fn coverage(&self) -> &[Option<Vec<u8>>] {
        &self.coverage
    }

    /// Makes the maps for this frame's `views` at `settings`' size and foveation, with
    /// `mask` applied when the settings ask for it and it has one mask per view.
    pub fn update(&mut self, gpu: &Gpu, mask: Option<&VisibilityMask>, settings: &ChainSettings, views: &[Eye]) {
        let layers = views.len().max(1) as u32;
        let mask = mask.filter(|m| settings.ao.mask && m.views.len() == views.len() && !views.is_empty());
        let coverage_key = CoverageKey {
            width: settings.width,
            height: settings.height,
            tangents: views.iter().map(|e| e.fov.tangents().map(f64::to_bits)).collect(),
            mask: mask.cloned(),
        };
        let rate_key = RateKey { coverage: coverage_key.clone(), foveation: settings.ao.foveation };
        if self.rate_key.as_ref() == Some(&rate_key) {
            return;
        }
        let (width, height) = (settings.width.max(1), settings.height.max(1));
        let coverage_changed = self.coverage_key.as_ref() != Some(&coverage_key);
        if coverage_changed {
            self.coverage = (0..views.len())
                .map(|i| mask.map(|m| m.views[i].coverage(width, height, views[i].fov.tangents())))
                .map(|c| c.filter(|c| c.contains(&0)))
                .collect();
            self.hidden_share = self
                .coverage
                .iter()
                .map(|c| c.as_ref().map_or(0.0, |c| c.iter().filter(|&&p| p == 0).count() as f64 / c.len() as f64))
                .collect();
        }
        let foveation = settings.ao.foveation.map();
        let maps: Vec<RateMap> = (0..layers as usize)
            .map(|i| {
                let tangents = views.get(i).map_or([-1.0, 1.0, 1.0, -1.0], |e| e.fov.tangents());
                RateMap::new(width, height, tangents, self.coverage.get(i).and_then(|c| c.as_deref()), &foveation)
            })
            .collect();
        let (tiles_x, tiles_y) = (maps[0].width, maps[0].height);
        let sizes_changed = self.tiles.width() != tiles_x
            || self.tiles.height() != tiles_y
            || self.tiles.depth_or_array_layers() != layers
            || self.pixels.width() != width
            || self.pixels.height() != height;
        if sizes_changed {
            let (tiles, pixels) = textures(gpu, width, height, layers, tiles_x, tiles_y);
            self.tiles = tiles;
            self.pixels = pixels;
            self.bind_group = bind_group(gpu, &self.tiles, &self.pixels);
        }
        if coverage_changed || sizes_changed {
            let shown = vec![255u8; (width * height) as usize];
            for layer in 0..layers {
                let pixels = self.coverage.get(layer as usize).and_then(|c| c.as_deref()).unwrap_or(&shown);
                upload(gpu, &self.pixels, layer, 0, (width, height), pixels);
            }
        }
        for (layer, map) in maps.iter().enumerate() {
            upload(gpu, &self.tiles, layer as u32, 0, (tiles_x, tiles_y), &map.tiles);
            upload(gpu, &self.tiles, layer as u32, 1, (tiles_x / 2, tiles_y / 2), &map.coarse);
        }
        self.coverage_key = Some(coverage_key);
        self.rate_key = Some(rate_key);
    }
}

fn textures(
    gpu: &Gpu,
    width: u32,
    height: u32,
    layers: u32,
    tiles_x: u32,
    tiles_y: u32,
) -> (wgpu::Texture, wgpu::Texture) {
    let texture = |label, width, height, mips| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
            mip_level_count: mips,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    };
    (texture("visibility rate map", tiles_x, tiles_y, 2), texture("visibility coverage", width, height, 1))
}

fn bind_group(gpu: &Gpu, tiles: &wgpu::Texture, pixels: &wgpu::Texture) -> wgpu::BindGroup {
    let view = |t: &wgpu::Texture| {
        t.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    };
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("visibility"),
        layout: &gpu.visibility_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view(tiles)) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view(pixels)) },
        ],
    })
}

fn upload(gpu: &Gpu, texture: &wgpu::Texture, layer: u32, mip: u32, (width, height): (u32, u32), bytes: &[u8]) {
    debug_assert_eq!(bytes.len(), (width * height) as usize);
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: mip,
            origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width), rows_per_image: Some(height) },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
}
