//! The textures of a frame graph: what the plan's passes write, allocated at their size
//! for the frame and kept while it holds; 1×1 placeholders for what binding lists name
//! but a pass does not read; and the textures imported from outside the graph (a host's
//! depth buffer). The renderer and the AO engine each own one.

use crate::gpu::layered_target::LayeredTarget;
use crate::gpu::uniforms::ao_extent;
use crate::gpu::Gpu;
use crate::graph::{Kind, Plan, Resource, Size, Written};
use crate::passes::DeclareContext;
use std::collections::{BTreeMap, HashMap};

/// The targets, placeholders and imported textures of one frame graph.
#[derive(Default)]
pub struct GraphTargets {
    /// Allocated and imported textures by resource (passes look them up here).
    pub targets: BTreeMap<Resource, LayeredTarget>,
    /// 1×1 stand-ins, by format, for what binding lists name but a pass does not read.
    pub placeholders: HashMap<wgpu::TextureFormat, LayeredTarget>,
}

impl GraphTargets {
    /// Binds `texture` (`layers` layers of its `aspect`) as the imported resource `r` for
    /// the next frames. Its views and the bind groups that hold them are made anew only
    /// when the texture changed.
    pub fn import(
        &mut self,
        gpu: &Gpu,
        r: Resource,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
        layers: u32,
    ) {
        debug_assert!(matches!(r.kind(), Kind::Imported), "{} is not an imported resource", r.name());
        let same = self.targets.get(&r).is_some_and(|t| t.texture == *texture && t.layers == layers);
        if !same {
            self.targets.insert(r, LayeredTarget::wrap(texture, r.name(), aspect, layers));
            gpu.invalidate_bind_groups();
        }
    }

    /// (Re)creates the targets this plan touches at their size for this frame; targets
    /// of another size are dropped, so a resource no pass needs costs no memory. Makes
    /// the placeholders the plan's passes bind in place of what they do not read.
    /// Imported textures are left as they are.
    pub fn allocate(&mut self, gpu: &Gpu, plan: &Plan, setup: &DeclareContext) {
        let device = &gpu.device;
        let max_side = device.limits().max_texture_dimension_2d;
        let extent_of = |r: Resource| extent(r, setup, max_side);
        let allocated = |r: &Resource| !matches!(r.kind(), Kind::Imported);
        let stale: Vec<Resource> = self
            .targets
            .iter()
            .filter(|(r, t)| allocated(r) && (t.extent() != extent_of(**r) || t.format != r.format_in(setup.chain)))
            .map(|(r, _)| *r)
            .collect();
        let mut changed = !stale.is_empty();
        for r in stale {
            self.targets.remove(&r);
        }
        for &r in plan.resources.iter().filter(|r| allocated(r)) {
            let Kind::Texture { written, .. } = r.kind() else { unreachable!("the plan resolves named outputs") };
            let target = self.targets.entry(r).or_insert_with(|| {
                changed = true;
                let usage = match written {
                    Written::Attachment => {
                        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING
                    }
                    // COPY_DST: tests poison targets by writing them.
                    Written::Storage => {
                        wgpu::TextureUsages::STORAGE_BINDING
                            | wgpu::TextureUsages::TEXTURE_BINDING
                            | wgpu::TextureUsages::COPY_DST
                    }
                };
                LayeredTarget::new(device, r.name(), r.format_in(setup.chain), extent_of(r), usage)
            });
            // Names are the identity of textures: two declarations under one name must agree.
            debug_assert_eq!(target.format, r.format_in(setup.chain), "two textures are named {}", r.name());
        }
        for decl in &plan.decls {
            for r in &decl.unbound {
                let format = r.format_in(setup.chain);
                self.placeholders.entry(format).or_insert_with(|| {
                    changed = true;
                    LayeredTarget::placeholder(device, "placeholder", format)
                });
            }
        }
        if changed {
            gpu.invalidate_bind_groups();
        }
    }
}

/// Width × height × layers of a texture this frame.
fn extent(r: Resource, setup: &DeclareContext, max_side: u32) -> (u32, u32, u32) {
    let p = setup.settings;
    let Kind::Texture { size, .. } = r.kind() else { unreachable!("only textures are allocated") };
    let (width, height) = match size {
        Size::Full => (p.width, p.height),
        Size::Occlusion => ao_extent(p.width, p.height, setup.settings.ao.resolution.is_half()),
        Size::Half => ao_extent(p.width, p.height, true),
        Size::Computed(extent) => return extent(setup, max_side),
    };
    (width, height, setup.views)
}
