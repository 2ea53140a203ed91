//! Copies layered textures back to the CPU (debug images, tests, error measurement).

use super::layered_target::LayeredTarget;
use super::Gpu;
use crate::error::{Error, Result};

/// Bytes of one texel for the formats vrao reads back.
fn texel_bytes(format: wgpu::TextureFormat) -> u32 {
    match format {
        wgpu::TextureFormat::Rgba8Unorm
        | wgpu::TextureFormat::Rgba8UnormSrgb
        | wgpu::TextureFormat::Bgra8Unorm
        | wgpu::TextureFormat::Bgra8UnormSrgb => 4,
        wgpu::TextureFormat::R32Float | wgpu::TextureFormat::Depth32Float => 4,
        wgpu::TextureFormat::Rgba16Float => 8,
        wgpu::TextureFormat::R16Float => 2,
        wgpu::TextureFormat::Rg32Uint => 8,
        wgpu::TextureFormat::Rgba32Float => 16,
        other => panic!("readback of {other:?} is not supported"), // programming error, not input
    }
}

/// A buffer the GPU copies into and the CPU maps to read.
fn staging_buffer(gpu: &Gpu, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    })
}

/// Submits `encoder` (its copies into `staging`), waits for the device, maps `staging`
/// and hands its bytes to `read`.
fn submit_and_read<T>(
    gpu: &Gpu,
    encoder: wgpu::CommandEncoder,
    staging: &wgpu::Buffer,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    gpu.queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait_idle()?;
    rx.recv()
        .map_err(|_| Error::Gpu("readback callback never ran".into()))?
        .map_err(|e| Error::Gpu(format!("readback failed: {e}")))?;
    let data = slice.get_mapped_range().map_err(|e| Error::Gpu(format!("mapping a readback buffer: {e}")))?;
    let value = read(&data);
    drop(data);
    staging.unmap();
    Ok(value)
}

/// The bytes of `source` (which has `COPY_SRC`) once the work submitted so far has run.
pub(crate) fn read_buffer(gpu: &Gpu, source: &wgpu::Buffer) -> Result<Vec<u8>> {
    let staging = staging_buffer(gpu, source.size());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, source.size());
    submit_and_read(gpu, encoder, &staging, <[u8]>::to_vec)
}

/// Raw bytes of every layer, rows tightly packed (the 256-byte row padding removed).
pub fn read_layers(gpu: &Gpu, target: &LayeredTarget) -> Result<Vec<Vec<u8>>> {
    let bpt = texel_bytes(target.format);
    let row = target.width * bpt;
    let padded_row = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let layer_bytes = padded_row as u64 * target.height as u64;
    let buffer = staging_buffer(gpu, layer_bytes * target.layers as u64);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let aspect =
        if target.format.is_depth_stencil_format() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture: &target.texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(target.height),
            },
        },
        wgpu::Extent3d { width: target.width, height: target.height, depth_or_array_layers: target.layers },
    );
    submit_and_read(gpu, encoder, &buffer, |data| {
        (0..target.layers as usize)
            .map(|layer| {
                let mut out = Vec::with_capacity((row * target.height) as usize);
                for y in 0..target.height as usize {
                    let start = layer * layer_bytes as usize + y * padded_row as usize;
                    out.extend_from_slice(&data[start..start + row as usize]);
                }
                out
            })
            .collect()
    })
}

/// Every layer as f32 values (channels interleaved), for float, depth and 8-bit formats.
pub fn read_layers_f32(gpu: &Gpu, target: &LayeredTarget) -> Result<Vec<Vec<f32>>> {
    let raw = read_layers(gpu, target)?;
    let half = matches!(target.format, wgpu::TextureFormat::Rgba16Float | wgpu::TextureFormat::R16Float);
    let unorm8 = matches!(target.format, wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb);
    Ok(raw
        .into_iter()
        .map(|bytes| {
            if unorm8 {
                // Each byte / 255: for an sRGB format, the encoded value.
                bytes.iter().map(|&b| b as f32 / 255.0).collect()
            } else if half {
                bytes.chunks_exact(2).map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()
            } else {
                bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
            }
        })
        .collect())
}
