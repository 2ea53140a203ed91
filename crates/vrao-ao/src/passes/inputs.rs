//! The textures the AO chain reads, by name: a renderer's G-buffer writes them (vrao's
//! does), or the engine's import pass makes them from a host's depth and normals.

use crate::graph::{Resource, Size};

/// Reversed-Z depth of every eye layer.
pub const DEPTH: Resource = Resource::attachment("depth", Size::Full, wgpu::TextureFormat::Depth32Float);
/// View-space unit normals; w is 1 on alpha-tested surfaces (cards), else 0.
pub const NORMALS: Resource = Resource::attachment("normals", Size::Full, wgpu::TextureFormat::Rgba16Float);
/// Each pixel's motion since the previous frame, of its eye and its object: xy the
/// previous uv minus this uv (uv 0..1 from the top left), z the previous distance along
/// the view's −z minus this one, w 1 where valid (0: the point was behind the previous
/// eye). Written only when the scene moves; a host hands its own to the AO engine.
pub const MOTION: Resource = Resource::attachment("motion", Size::Full, wgpu::TextureFormat::Rgba16Float);
/// The direct light leaving each pixel's surface (outgoing radiance, RGB) with its view
/// distance, packed (common.wgsl `pack_direct`): what SSDO's bounce sends from each
/// occluding sample. vrao's renderer writes it (its direct-light pass); the AO engine
/// packs a host's radiance texture into it.
pub const DIRECT_LIGHT: Resource = Resource::storage("direct", Size::Full, wgpu::TextureFormat::Rg32Uint);
/// The second depth layer (reversed-Z, `Depth32Float`): the nearest surface at least the
/// settings' `layer_separation` behind [`DEPTH`], 0 where nothing lies behind it. vrao's
/// renderer peels it (its depth-peel pass) when the occlusion reads two layers. The
/// depth's lowest mantissa bit is 1 where that surface faces the eye (a front face: the
/// first layer is a sheet and the span between the layers is air, so the occlusion keeps
/// its thickness there); a host's layer is imported with the bit cleared.
pub const DEPTH_LAYER_2: Resource =
    Resource::attachment("depth-layer-2", Size::Full, wgpu::TextureFormat::Depth32Float);
