//! A list of work items that one dispatch appends on the GPU and a second, indirect
//! dispatch runs over (64 items to a workgroup): the buffer layout every such list shares
//! (WGSL: `groups_x: atomic<u32>, groups_y: u32, groups_z: u32, count: atomic<u32>`, then
//! the items), reset each frame by a copy, its header copied out as the indirect
//! arguments. Nothing is read back in a frame.

use super::RecordContext;
use crate::gpu::Gpu;
use wgpu::util::DeviceExt;

/// Bytes of the list's header: the indirect arguments (x, y, z), then the count.
pub(crate) const HEADER_BYTES: u64 = 16;

/// One list, kept from frame to frame.
pub(crate) struct IndirectList {
    label: &'static str,
    /// The header, then room for every item of the frame.
    list: Option<wgpu::Buffer>,
    /// What each frame's header starts from (no items, y = z = 1) and one item: what
    /// binds in the list's place for the dispatches that do not use it.
    header: wgpu::Buffer,
    /// The header copied out of the list (a buffer may not be both a dispatch's
    /// read-write binding and its arguments).
    arguments: wgpu::Buffer,
}

impl IndirectList {
    /// An empty list; `label` names its buffers.
    pub(crate) fn new(gpu: &Gpu, label: &'static str) -> Self {
        let device = &gpu.device;
        let header = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(&[0u32, 1, 1, 0, 0]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let arguments = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: HEADER_BYTES,
            usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        IndirectList { label, list: None, header, arguments }
    }

    /// What binds in the list's place for the dispatches that do not use it.
    pub(crate) fn stand_in(&self) -> wgpu::Buffer {
        self.header.clone()
    }

    /// Empties the list, with room for `items`, and returns it (a clone of the one
    /// buffer: wgpu buffers are shared handles).
    pub(crate) fn start(&mut self, ctx: &mut RecordContext, items: u32) -> wgpu::Buffer {
        let size = HEADER_BYTES + 4 * u64::from(items.max(1));
        if self.list.as_ref().is_none_or(|b| b.size() < size) {
            self.list = Some(ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let list = self.list.clone().expect("made above");
        ctx.encoder.copy_buffer_to_buffer(&self.header, 0, &list, 0, HEADER_BYTES);
        list
    }

    /// Copies the list's header (filled by the appending dispatch) out as the indirect
    /// dispatch's arguments ([`IndirectList::arguments`]).
    pub(crate) fn take_arguments(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(list) = &self.list {
            encoder.copy_buffer_to_buffer(list, 0, &self.arguments, 0, HEADER_BYTES);
        }
    }

    /// The indirect dispatch's arguments, at offset 0.
    pub(crate) fn arguments(&self) -> &wgpu::Buffer {
        &self.arguments
    }

    /// The list itself (header and items), once started.
    pub(crate) fn buffer(&self) -> Option<&wgpu::Buffer> {
        self.list.as_ref()
    }
}
