//! The checks every host texture the engine reads goes through: its size, its layers (one
//! per view), its sample count and its usage, each refusal naming the input.

use super::AoConfig;
use crate::error::{Error, Result};

/// Refuses a texture of another size, too few layers, multisampled or not bindable.
pub(crate) fn check_texture(what: &str, texture: &wgpu::Texture, config: &AoConfig) -> Result<()> {
    check_texture_size(what, texture, config)?;
    if texture.sample_count() != 1 {
        return Err(Error::input(format!(
            "{what}: {} samples per pixel; the engine resolves only the depth and normals, so resolve this one first",
            texture.sample_count()
        )));
    }
    Ok(())
}

/// Refuses a texture of another size, too few layers or not bindable.
pub(crate) fn check_texture_size(what: &str, texture: &wgpu::Texture, config: &AoConfig) -> Result<()> {
    let size = texture.size();
    if (size.width, size.height) != (config.width, config.height) {
        return Err(Error::input(format!(
            "{what}: {}×{} does not match the engine's {}×{}",
            size.width, size.height, config.width, config.height
        )));
    }
    if size.depth_or_array_layers < config.views || texture.dimension() != wgpu::TextureDimension::D2 {
        return Err(Error::input(format!(
            "{what}: a 2D texture with {} layer(s) cannot hold {} view(s)",
            size.depth_or_array_layers, config.views
        )));
    }
    if !texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return Err(Error::input(format!("{what}: the texture lacks TEXTURE_BINDING usage")));
    }
    Ok(())
}
