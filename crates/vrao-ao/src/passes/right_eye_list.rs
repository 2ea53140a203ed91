//! The right eye's list of work the left eye cannot give it, shared by the passes that
//! reuse the left eye's results: a first right-eye dispatch copies what it can and
//! appends the rest (pixels or quads) to an [`IndirectList`], and a second, indirect
//! dispatch runs over just those (64 to a workgroup). A report reads the last frame's
//! counts. A renderer's pass that reuses the left eye (its composite) keeps its list in
//! one too.

use super::indirect_list::{IndirectList, HEADER_BYTES};
use super::occlusion::{AO_GEOMETRY, AO_RAW};
use super::{RecordContext, RightEyeTiles};
use crate::gpu::kernel::{Bind, Kernel, TILE};
use crate::gpu::Gpu;
use crate::graph::Resource;

/// One pass's list, kept from frame to frame.
pub struct RightEyeList {
    list: IndirectList,
    /// Tiles (8×8 workgroups) of the right eye's image in the last frame that listed
    /// items (0: none did), and that frame's index.
    tiles: u32,
    frame: u64,
    /// Workgroups the list's dispatch ran before its items that frame (GTAO's folded
    /// dispatch: the left eye's interior tiles).
    before_items: u32,
}

impl RightEyeList {
    /// An empty list; `label` names its buffers.
    pub fn new(gpu: &Gpu, label: &'static str) -> Self {
        RightEyeList { list: IndirectList::new(gpu, label), tiles: 0, frame: 0, before_items: 0 }
    }

    /// What binds in the list's place before the right eye's dispatches.
    pub fn stand_in(&self) -> wgpu::Buffer {
        self.list.stand_in()
    }

    /// Starts this frame's list, with room for `items`, over an image of `tiles` tiles;
    /// returns it.
    fn start(&mut self, ctx: &mut RecordContext, items: u32, tiles: u32) -> wgpu::Buffer {
        (self.tiles, self.frame, self.before_items) = (tiles, ctx.setup.frame_index, 0);
        self.list.start(ctx, items)
    }

    /// GTAO's right eye, folded into the left eye's dispatch (gtao.wgsl `FOLDED`): starts
    /// the list of a `width` × `height` image, whose dispatch runs `before_items`
    /// workgroups of the left eye first, and returns it; its dispatch arguments follow
    /// [`RightEyeList::take_arguments`].
    pub(crate) fn start_folded(
        &mut self,
        ctx: &mut RecordContext,
        (width, height): (u32, u32),
        before_items: u32,
    ) -> wgpu::Buffer {
        let list = self.start(ctx, width * height, width.div_ceil(TILE) * height.div_ceil(TILE));
        self.before_items = before_items;
        list
    }

    /// Copies the list's header out as its indirect dispatch's arguments.
    pub(crate) fn take_arguments(&self, encoder: &mut wgpu::CommandEncoder) {
        self.list.take_arguments(encoder);
    }

    /// The indirect dispatch's arguments (offset 0).
    pub(crate) fn arguments(&self) -> &wgpu::Buffer {
        self.list.arguments()
    }

    /// The right eye after the left (occlusion/right_eye.wgsl): `classify` copies what
    /// the left eye gives and lists the occlusion pixels left to estimate, then `listed`
    /// runs over those by an indirect dispatch. Both write layer 1 of the raw occlusion
    /// and its geometry alone and read the left eye's layer 0 of both (bindings 7 and
    /// 8), the list at 9; `after_list` fills the technique's own bindings after it.
    /// `deferred`: a kernel the listed dispatch hands some of its pixels to through a
    /// list of its own (started by the caller, bound in `after_list`), run last over
    /// those by an indirect dispatch with the same bindings (GTAO's marches that cross
    /// the inner border). GTAO can fold its right eye into the left eye's dispatch
    /// instead ([`RightEyeList::start_folded`]).
    pub(crate) fn record_right_eye(
        &mut self,
        ctx: &mut RecordContext,
        binds: &[Bind],
        after_list: &[wgpu::BindingResource],
        [classify, listed]: [&Kernel; 2],
        deferred: Option<(&Kernel, &IndirectList)>,
        (width, height): (u32, u32),
    ) {
        let list = self.start(ctx, width * height, width.div_ceil(TILE) * height.div_ceil(TILE));
        let views = RightEyeViews::new(ctx);
        let resources = views.bind(ctx, binds, &list, after_list);
        let device = &ctx.gpu.device;
        let visibility = ctx.visibility.bind_group();
        classify.dispatch(device, ctx.encoder, visibility, &resources, (width, height, 1));
        self.list.take_arguments(ctx.encoder);
        listed.dispatch_indirect(device, ctx.encoder, visibility, &resources, self.list.arguments(), 0);
        if let Some((kernel, list)) = deferred {
            list.take_arguments(ctx.encoder);
            kernel.dispatch_indirect(device, ctx.encoder, visibility, &resources, list.arguments(), 0);
        }
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
        self.list.take_arguments(ctx.encoder);
        fallback.dispatch_indirect(device, ctx.encoder, visibility, &resources, self.list.arguments(), 0);
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
        let bytes = crate::gpu::readback::read_buffer(gpu, self.list.buffer()?).ok()?;
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
        self.counts(&crate::gpu::readback::read_buffer(gpu, self.list.arguments()).ok()?, pass)
    }

    /// The counts in a header read back (its first `HEADER_BYTES`).
    fn counts(&self, header: &[u8], pass: &'static str) -> Option<RightEyeTiles> {
        let word = |k: usize| Some(u32::from_le_bytes(header.get(4 * k..4 * k + 4)?.try_into().ok()?));
        let computed = word(0)?.checked_sub(self.before_items)?;
        Some(RightEyeTiles { pass, computed, items: word(3)?, total: self.tiles, frame: self.frame })
    }
}

/// The views a right-eye dispatch binds: layer 1 of the raw occlusion and its geometry as
/// its outputs, and their left-eye layer 0 to read.
pub(crate) struct RightEyeViews {
    /// Of the raw occlusion, then of its geometry: [left, right].
    occlusion: [wgpu::TextureView; 2],
    geometry: [wgpu::TextureView; 2],
}

impl RightEyeViews {
    /// The views of this frame's targets.
    pub(crate) fn new(ctx: &RecordContext) -> Self {
        RightEyeViews {
            occlusion: [0, 1].map(|layer| ctx.layer_view(AO_RAW, layer)),
            geometry: [0, 1].map(|layer| ctx.layer_view(AO_GEOMETRY, layer)),
        }
    }

    /// `binds` for a right-eye dispatch: the right eye's layers as the outputs, the left
    /// eye's at bindings 7 and 8, `list` at 9, then `after_list`.
    pub(crate) fn bind<'a: 'b, 'b>(
        &'b self,
        ctx: &RecordContext<'a>,
        binds: &[Bind],
        list: &'b wgpu::Buffer,
        after_list: &[wgpu::BindingResource<'b>],
    ) -> Vec<wgpu::BindingResource<'b>> {
        let view = wgpu::BindingResource::TextureView;
        let mut own = vec![view(&self.occlusion[0]), view(&self.geometry[0]), list.as_entire_binding()];
        own.extend_from_slice(after_list);
        ctx.bind_overriding(binds, &own, &[(AO_RAW, view(&self.occlusion[1])), (AO_GEOMETRY, view(&self.geometry[1]))])
    }
}
