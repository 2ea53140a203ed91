//! The right eye's list of work the left eye cannot give it, shared by the passes that
//! reuse the left eye's results: a first right-eye dispatch copies what it can and
//! appends the rest (pixels or quads) to a list on the GPU, whose header holds the
//! workgroup counts of a second, indirect dispatch over just those (64 to a workgroup).
//! Nothing is read back in a frame; a report reads the last frame's counts. A renderer's
//! pass that reuses the left eye (its composite) keeps its list in one too.

use super::occlusion::{AO_GEOMETRY, AO_RAW};
use super::{RecordContext, RightEyeTiles};
use crate::gpu::kernel::{Bind, Kernel, TILE};
use crate::gpu::Gpu;
use crate::graph::Resource;
use wgpu::util::DeviceExt;

/// Bytes of the list's header: the indirect arguments (x, y, z), then the count (WGSL:
/// `groups_x: atomic<u32>, groups_y, groups_z, count: atomic<u32>`, then the items).
const HEADER_BYTES: u64 = 16;

/// One pass's list, kept from frame to frame.
pub struct RightEyeList {
    label: &'static str,
    /// The header, then room for every item of the frame.
    list: Option<wgpu::Buffer>,
    /// What each frame's header starts from (no items, y = z = 1) and one item: what
    /// binds in the list's place for the dispatches that do not use it.
    header: wgpu::Buffer,
    /// The header copied out of the list (a buffer may not be both a dispatch's
    /// read-write binding and its arguments).
    arguments: wgpu::Buffer,
    /// Tiles (8×8 workgroups) of the right eye's image in the last frame that listed
    /// items (0: none did), and that frame's index.
    tiles: u32,
    frame: u64,
}

impl RightEyeList {
    /// An empty list; `label` names its buffers.
    pub fn new(gpu: &Gpu, label: &'static str) -> Self {
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
        RightEyeList { label, list: None, header, arguments, tiles: 0, frame: 0 }
    }

    /// What binds in the list's place before the right eye's dispatches.
    pub fn stand_in(&self) -> wgpu::Buffer {
        self.header.clone()
    }

    /// Starts this frame's list, with room for `items`, over an image of `tiles` tiles;
    /// returns it (a clone of the one buffer: wgpu buffers are shared handles).
    fn start(&mut self, ctx: &mut RecordContext, items: u32, tiles: u32) -> wgpu::Buffer {
        let size = HEADER_BYTES + 4 * u64::from(items.max(1));
        if self.list.as_ref().is_none_or(|b| b.size() < size) {
            self.list = Some(ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        (self.tiles, self.frame) = (tiles, ctx.setup.frame_index);
        let list = self.list.clone().expect("made above");
        ctx.encoder.copy_buffer_to_buffer(&self.header, 0, &list, 0, HEADER_BYTES);
        list
    }

    /// Copies the list's header (filled by the first dispatch) out for the indirect one.
    fn take_arguments(&self, encoder: &mut wgpu::CommandEncoder, list: &wgpu::Buffer) {
        encoder.copy_buffer_to_buffer(list, 0, &self.arguments, 0, HEADER_BYTES);
    }

    /// The right eye after the left (occlusion/right_eye.wgsl): `classify` copies what
    /// the left eye gives and lists the occlusion pixels left to estimate, then `listed`
    /// runs over those by an indirect dispatch. Both write layer 1 of the raw occlusion
    /// and its geometry alone and read the left eye's layer 0 of both (bindings 7 and
    /// 8), the list at 9; `after_list` fills the technique's own bindings after it.
    pub(crate) fn record_right_eye(
        &mut self,
        ctx: &mut RecordContext,
        binds: &[Bind],
        after_list: &[wgpu::BindingResource],
        [classify, listed]: [&Kernel; 2],
        (width, height): (u32, u32),
    ) {
        let list = self.start(ctx, width * height, width.div_ceil(TILE) * height.div_ceil(TILE));
        let (ao_right, geometry_right) = (ctx.layer_view(AO_RAW, 1), ctx.layer_view(AO_GEOMETRY, 1));
        let (ao_left, geometry_left) = (ctx.layer_view(AO_RAW, 0), ctx.layer_view(AO_GEOMETRY, 0));
        let view = wgpu::BindingResource::TextureView;
        let mut own = vec![view(&ao_left), view(&geometry_left), list.as_entire_binding()];
        own.extend_from_slice(after_list);
        let resources =
            ctx.bind_overriding(binds, &own, &[(AO_RAW, view(&ao_right)), (AO_GEOMETRY, view(&geometry_right))]);
        let device = &ctx.gpu.device;
        let visibility = ctx.visibility.bind_group();
        classify.dispatch(device, ctx.encoder, visibility, &resources, (width, height, 1));
        self.take_arguments(ctx.encoder, &list);
        listed.dispatch_indirect(device, ctx.encoder, visibility, &resources, &self.arguments, 0);
    }

    /// The right eye after the left, one invocation per quad of 2×2 pixels (the
    /// upsampling's and the composite's reuse of the left eye's final AO): `copy` takes
    /// what the left eye gives and lists the quads it cannot fully, then `fallback` runs
    /// over those by an indirect dispatch. Both write layer 1 of `output` alone and read
    /// its left-eye layer 0 and the list as the binding list's two `Bind::Own` entries,
    /// in that order. `quads`: the image's quads, width × height.
    pub fn record_right_eye_quads(
        &mut self,
        ctx: &mut RecordContext,
        binds: &[Bind],
        output: Resource,
        [copy, fallback]: [&Kernel; 2],
        (width, height): (u32, u32),
    ) {
        let list = self.start(ctx, width * height, width.div_ceil(TILE) * height.div_ceil(TILE));
        let (right, left) = (ctx.layer_view(output, 1), ctx.layer_view(output, 0));
        let view = wgpu::BindingResource::TextureView;
        let resources = ctx.bind_overriding(binds, &[view(&left), list.as_entire_binding()], &[(output, view(&right))]);
        let device = &ctx.gpu.device;
        let visibility = ctx.visibility.bind_group();
        copy.dispatch(device, ctx.encoder, visibility, &resources, (width, height, 1));
        self.take_arguments(ctx.encoder, &list);
        fallback.dispatch_indirect(device, ctx.encoder, visibility, &resources, &self.arguments, 0);
    }

    /// Marks a frame that did not reuse the left eye: nothing to report.
    pub fn skip(&mut self) {
        self.tiles = 0;
    }

    /// The last listing frame's counts and its listed occlusion pixels, as (x, y), read
    /// back (blocking; for debug images). Not for the upsampling's quads, which carry a
    /// mask beside their position (joint_upsample.wgsl `pack_quad`).
    /// One readback: the list begins with the header the arguments were copied from.
    pub(crate) fn read_items(&self, gpu: &Gpu, pass: &'static str) -> Option<(RightEyeTiles, Vec<[u32; 2]>)> {
        if self.tiles == 0 {
            return None;
        }
        let bytes = crate::gpu::readback::read_buffer(gpu, self.list.as_ref()?).ok()?;
        let tiles = self.counts(&bytes, pass)?;
        let first = HEADER_BYTES as usize;
        let listed = bytes.get(first..first + 4 * tiles.items as usize)?;
        let items = listed.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        Some((tiles, items.map(|packed| [packed & 0xffff, packed >> 16]).collect()))
    }

    /// The last listing frame's counts, read back (blocking).
    pub fn read(&self, gpu: &Gpu, pass: &'static str) -> Option<RightEyeTiles> {
        if self.tiles == 0 {
            return None;
        }
        self.counts(&crate::gpu::readback::read_buffer(gpu, &self.arguments).ok()?, pass)
    }

    /// The counts in a header read back (its first `HEADER_BYTES`).
    fn counts(&self, header: &[u8], pass: &'static str) -> Option<RightEyeTiles> {
        let word = |k: usize| Some(u32::from_le_bytes(header.get(4 * k..4 * k + 4)?.try_into().ok()?));
        Some(RightEyeTiles { pass, computed: word(0)?, items: word(3)?, total: self.tiles, frame: self.frame })
    }
}
