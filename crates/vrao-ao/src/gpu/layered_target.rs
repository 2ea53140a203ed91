//! Layered render targets: one 2D array texture, layer 0 = left eye, layer 1 = right eye
//! (one layer for a mono view).

/// A 2D array texture with a view of the whole array and one view per layer (a clone
/// shares the texture: wgpu handles are reference-counted).
#[derive(Clone)]
pub struct LayeredTarget {
    /// The texture itself (for copies and readback).
    pub texture: wgpu::Texture,
    /// All layers, as `texture_2d_array` / `texture_storage_2d_array` / multiview attachment.
    pub array_view: wgpu::TextureView,
    /// One single-layer 2D view per layer, for per-eye render passes.
    pub layer_views: Vec<wgpu::TextureView>,
    /// The texel format.
    pub format: wgpu::TextureFormat,
    /// Width of each layer in pixels.
    pub width: u32,
    /// Height of each layer in pixels.
    pub height: u32,
    /// Number of layers: 2 for stereo, 1 for mono.
    pub layers: u32,
}

impl LayeredTarget {
    /// Makes a `width` × `height` × `layers` texture with the given usages and its views.
    pub fn new(
        device: &wgpu::Device,
        label: &str,
        format: wgpu::TextureFormat,
        (width, height, layers): (u32, u32, u32),
        usage: wgpu::TextureUsages,
    ) -> LayeredTarget {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            // Every target can be read back (debug outputs, tests, measurements).
            usage: usage | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            array_layer_count: Some(layers),
            ..Default::default()
        });
        let layer_views = super::raster::layer_views(&texture, label, layers);
        LayeredTarget { texture, array_view, layer_views, format, width, height, layers }
    }

    /// A 1×1, 2-layer texture to bind where a layout has a slot the chosen shader
    /// variant never reads (wgpu needs every binding filled).
    pub fn placeholder(device: &wgpu::Device, label: &str, format: wgpu::TextureFormat) -> LayeredTarget {
        LayeredTarget::new(device, label, format, (1, 1, 2), wgpu::TextureUsages::TEXTURE_BINDING)
    }

    /// A texture someone else made (a host's depth buffer), seen as `layers` layers of its
    /// `aspect`; no per-layer views.
    pub fn wrap(texture: &wgpu::Texture, label: &str, aspect: wgpu::TextureAspect, layers: u32) -> LayeredTarget {
        let size = texture.size();
        // A multisampled texture has only 2D views (of one layer): its reader (the AO
        // engine's import) makes one per layer itself.
        let (dimension, array_layer_count) = match texture.sample_count() {
            1 => (wgpu::TextureViewDimension::D2Array, layers),
            _ => (wgpu::TextureViewDimension::D2, 1),
        };
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(dimension),
            aspect,
            array_layer_count: Some(array_layer_count),
            ..Default::default()
        });
        LayeredTarget {
            texture: texture.clone(),
            array_view,
            layer_views: Vec::new(),
            format: texture.format(),
            width: size.width,
            height: size.height,
            layers,
        }
    }

    /// (width, height, layers).
    pub fn extent(&self) -> (u32, u32, u32) {
        (self.width, self.height, self.layers)
    }
}
