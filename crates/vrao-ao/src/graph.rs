//! The frame graph. Each pass declares, in one builder chain ([`PassDecl`]), what it
//! reads and writes (mostly through its kernels' binding lists), what it provides under a
//! named output, and whether the scene and settings let it exist at all. Given the
//! outputs a frame must produce, the graph keeps exactly the passes those outputs depend
//! on and says why every other pass was left out. Passes are declared in execution
//! order, so the kept ones run in that order.
//!
//! Textures are [`Resource`] handles declared as constants by the pass that creates
//! them, with their size class and format; there is no table of every texture. Named
//! outputs ([`OCCLUSION`], [`FINAL_AO`]) are aliases: each pass on the AO chain provides
//! its result under one, and a reader of the alias gets whatever the last enabled pass
//! before it provided.

use crate::error::{Error, Result};
use crate::gpu::kernel::Bind;
use crate::resource::ChainLayout;
pub(crate) use crate::resource::{Kind, Resource, Size, Written, FINAL_AO, OCCLUSION, PIXEL_MOTION};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

/// What a pass declares for one frame.
#[derive(Clone, Debug)]
pub struct PassDecl {
    /// The pass's name, as `--explain` and the GPU timings show it.
    pub name: &'static str,
    /// Resources the pass reads (named outputs resolved once planned).
    pub reads: Vec<Resource>,
    /// Resources the pass writes.
    pub writes: Vec<Resource>,
    /// (named output, what the pass provides under it).
    pub provides: Vec<(Resource, Resource)>,
    /// Reads a binding list names that the pass does not read this frame: a placeholder
    /// of the same format is bound instead.
    pub unbound: Vec<Resource>,
    /// Whether the pass is part of the occlusion's cost (what the governor changes and
    /// the bench times).
    pub occlusion_cost: bool,
    /// `Some(reason)` when the scene or settings rule the pass out for this frame.
    pub disabled: Option<String>,
    /// What `--explain` should add about work left out inside a running pass.
    pub note: Option<String>,
    /// Named outputs read, and the textures they stood for at this pass (filled by the plan).
    pub resolved: Vec<(Resource, Resource)>,
}

impl PassDecl {
    /// A pass that reads and writes nothing yet.
    pub fn new(name: &'static str) -> PassDecl {
        PassDecl {
            name,
            reads: Vec::new(),
            writes: Vec::new(),
            provides: Vec::new(),
            unbound: Vec::new(),
            occlusion_cost: false,
            disabled: None,
            note: None,
            resolved: Vec::new(),
        }
    }

    /// Adds a resource the pass reads (one it wrote itself earlier in the chain is
    /// internal to the pass and not a read).
    pub fn read(mut self, r: Resource) -> Self {
        if !self.writes.contains(&r) && !self.reads.contains(&r) {
            self.reads.push(r);
        }
        self
    }

    /// Adds a resource the pass writes.
    pub fn write(mut self, r: Resource) -> Self {
        if !self.writes.contains(&r) {
            self.writes.push(r);
        }
        self
    }

    /// Reads and writes what a kernel's binding list names, in its order.
    pub fn bindings(self, binds: &[Bind]) -> Self {
        binds.iter().fold(self, |decl, bind| match *bind {
            Bind::Read(r) => decl.read(r),
            Bind::Write(r) => decl.write(r),
            _ => decl,
        })
    }

    /// This frame the pass does not read `r`, which its binding list names: it is not a
    /// dependency and a placeholder is bound in its place.
    pub fn unbind(mut self, r: Resource) -> Self {
        self.reads.retain(|x| *x != r);
        self.unbound.push(r);
        self
    }

    /// Provides `texture` (which the pass writes) under the named output `alias`.
    pub fn provide(mut self, alias: Resource, texture: Resource) -> Self {
        self.provides.push((alias, texture));
        self
    }

    /// Marks the pass as part of the occlusion's cost.
    pub fn occlusion_cost(mut self) -> Self {
        self.occlusion_cost = true;
        self
    }

    /// Adds what `--explain` says about work left out inside the pass (after any earlier note).
    pub fn note(mut self, note: impl Into<String>) -> Self {
        let note = note.into();
        self.note = Some(match self.note {
            Some(earlier) => format!("{earlier}; {note}"),
            None => note,
        });
        self
    }

    /// Rules the pass out when `condition` holds, with `reason` shown by `--explain`.
    pub fn disabled_if(mut self, condition: bool, reason: impl Into<String>) -> Self {
        if condition && self.disabled.is_none() {
            self.disabled = Some(reason.into());
        }
        self
    }

    /// The texture `r` stands for in this pass: itself, or what a named output resolved to.
    pub fn resolve(&self, r: Resource) -> Resource {
        self.resolved.iter().find(|(alias, _)| *alias == r).map_or(r, |(_, texture)| *texture)
    }
}

/// The passes one frame runs and the ones it leaves out.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Indices into the declarations, in execution order.
    pub run: Vec<usize>,
    /// Names of the passes that run, in execution order.
    pub names: Vec<&'static str>,
    /// The declarations of the passes that run, named outputs resolved.
    pub decls: Vec<PassDecl>,
    /// Notes of running passes (work they leave out internally).
    pub notes: Vec<(&'static str, String)>,
    /// (pass, reason) for every pass that does not run.
    pub left_out: Vec<(&'static str, String)>,
    /// Every texture a running pass reads or writes (what the frame must allocate; the
    /// imported textures are not among them).
    pub resources: BTreeSet<Resource>,
    /// Each named output and the texture it stands for after the last pass.
    pub aliases: BTreeMap<Resource, Resource>,
}

impl PartialEq for Plan {
    fn eq(&self, other: &Self) -> bool {
        self.run == other.run && self.left_out == other.left_out && self.notes == other.notes
    }
}

/// Bytes a frame's occlusion passes move per full-resolution pixel of one view, counted
/// from their declared textures: each texture a pass writes once, each it reads once
/// (the taps a kernel makes within a texture are not counted; the same on every machine).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelTraffic {
    /// Bytes written per pixel.
    pub written: f64,
    /// Bytes read per pixel.
    pub read: f64,
}

impl Plan {
    /// Whether the pass of this name runs.
    pub fn runs(&self, name: &str) -> bool {
        self.names.contains(&name)
    }

    /// The texture `r` stands for after the frame: itself, or what a named output
    /// resolved to (`None` for a named output no enabled pass provides).
    pub fn resolve(&self, r: Resource) -> Option<Resource> {
        if r.is_alias() {
            self.aliases.get(&r).copied()
        } else {
            Some(r)
        }
    }

    /// The running passes that make up the occlusion's cost, in order.
    pub fn occlusion_passes(&self) -> Vec<&'static str> {
        self.decls.iter().filter(|d| d.occlusion_cost).map(|d| d.name).collect()
    }

    /// The traffic of the passes counted as the occlusion's cost, with the chain laid out
    /// as `chain` and the occlusion at half resolution when `half_res` (an
    /// occlusion-sized texel then stands for four pixels).
    pub fn occlusion_traffic(&self, chain: ChainLayout, half_res: bool) -> PixelTraffic {
        let share = |r: &Resource| match r.kind() {
            Kind::Texture { size: Size::Full, .. } | Kind::Imported => Some(1.0),
            Kind::Texture { size: Size::Occlusion, .. } => Some(if half_res { 0.25 } else { 1.0 }),
            Kind::Texture { size: Size::Half, .. } => Some(0.25),
            // Light-space maps and named outputs have no per-pixel size.
            Kind::Texture { size: Size::Computed(_), .. } | Kind::Alias { .. } => None,
        };
        // A depth-stencil format counts its depth; colour formats ignore the aspect.
        let bytes = |r: &Resource| {
            let texel = r.format_in(chain).block_copy_size(Some(wgpu::TextureAspect::DepthOnly));
            share(r).zip(texel).map_or(0.0, |(share, texel)| share * f64::from(texel))
        };
        let mut traffic = PixelTraffic::default();
        for decl in self.decls.iter().filter(|d| d.occlusion_cost) {
            let resolved = decl.reads.iter().filter(|r| !decl.unbound.contains(r)).map(|r| decl.resolve(*r));
            traffic.read += resolved.map(|r| bytes(&r)).sum::<f64>();
            traffic.written += decl.writes.iter().map(bytes).sum::<f64>();
        }
        traffic
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "passes that run, in order:")?;
        for name in &self.names {
            writeln!(f, "  ran       {name}")?;
            for (_, note) in self.notes.iter().filter(|(n, _)| n == name) {
                writeln!(f, "              {note}")?;
            }
        }
        if self.left_out.is_empty() {
            writeln!(f, "no pass was left out")?;
        } else {
            writeln!(f, "passes left out:")?;
            for (name, why) in &self.left_out {
                writeln!(f, "  left out  {name}: {why}")?;
            }
        }
        Ok(())
    }
}

/// Named outputs as provided so far, in declaration order.
#[derive(Default)]
struct Provided(BTreeMap<Resource, Resource>);

impl Provided {
    /// What `alias` stands for now: the last provider's texture, or its fallback's.
    fn get(&self, alias: Resource) -> Option<Resource> {
        match (self.0.get(&alias), alias.kind) {
            (Some(texture), _) => Some(*texture),
            (None, Kind::Alias { fallback: Some(fallback) }) => self.get(*fallback),
            _ => None,
        }
    }
}

/// Resolves every named output the passes read, then keeps the passes `outputs` depend
/// on. `imported` are textures the frame brings from outside the graph (a host's depth
/// buffer, the renderer's G-buffer handed to the AO engine): they need no producing pass,
/// and the graph neither allocates nor drops them. An output that no enabled pass
/// produces is an error naming it (a renderer bug or an impossible request, never
/// silently dropped).
pub fn plan(decls: &[PassDecl], outputs: &[Resource], imported: &[Resource]) -> Result<Plan> {
    let (decls, provided) = resolve_aliases(decls)?;
    // Each named output a pass provides or the frame asks for, as it stands after the last pass.
    let named = decls.iter().flat_map(|d| d.provides.iter().map(|p| p.0)).chain(outputs.iter().copied());
    let aliases: BTreeMap<Resource, Resource> =
        named.filter(|r| r.is_alias()).filter_map(|alias| Some((alias, provided.get(alias)?))).collect();
    let mut needed = BTreeSet::new();
    for &output in outputs {
        let texture = if output.is_alias() { aliases.get(&output).copied() } else { Some(output) };
        needed.insert(
            texture.ok_or_else(|| Error::Plan(format!("nothing provides '{}' for this frame", output.name())))?,
        );
    }
    let mut keep = vec![false; decls.len()];
    // Walk backwards: a pass is kept if it writes something needed downstream.
    for (i, decl) in decls.iter().enumerate().rev() {
        if decl.disabled.is_some() {
            continue;
        }
        if decl.writes.iter().any(|w| needed.contains(w)) {
            keep[i] = true;
            needed.extend(decl.reads.iter().copied());
        }
    }
    for r in &needed {
        let produced = imported.contains(r) || decls.iter().zip(&keep).any(|(d, k)| *k && d.writes.contains(r));
        if !produced {
            return Err(Error::Plan(format!("nothing produces '{}' for this frame", r.name())));
        }
    }
    let mut plan = Plan {
        run: Vec::new(),
        names: Vec::new(),
        decls: Vec::new(),
        notes: Vec::new(),
        left_out: Vec::new(),
        resources: needed.into_iter().filter(|r| !imported.contains(r)).collect(),
        aliases,
    };
    for (i, decl) in decls.into_iter().enumerate() {
        if keep[i] {
            plan.resources.extend(decl.writes.iter().copied());
            plan.run.push(i);
            plan.names.push(decl.name);
            if let Some(note) = &decl.note {
                plan.notes.push((decl.name, note.clone()));
            }
            plan.decls.push(decl);
        } else if let Some(reason) = &decl.disabled {
            plan.left_out.push((decl.name, reason.clone()));
        } else {
            let writes: Vec<_> = decl.writes.iter().map(|w| w.name()).collect();
            plan.left_out
                .push((decl.name, format!("nothing this frame needs reads its output ({})", writes.join(", "))));
        }
    }
    Ok(plan)
}

/// Replaces each named output an enabled pass reads by what the enabled passes before it
/// provided, recording the substitution in the pass's `resolved`; also returns what the
/// named outputs stand for after the last pass.
fn resolve_aliases(decls: &[PassDecl]) -> Result<(Vec<PassDecl>, Provided)> {
    let mut provided = Provided::default();
    let mut resolved = decls.to_vec();
    for decl in resolved.iter_mut() {
        if decl.disabled.is_some() {
            continue;
        }
        for read in decl.reads.iter_mut().filter(|r| r.is_alias()) {
            let alias = *read;
            let texture = provided.get(alias).ok_or_else(|| {
                Error::Plan(format!("pass '{}' reads '{}', which no pass before it provides", decl.name, alias.name()))
            })?;
            decl.resolved.push((alias, texture));
            *read = texture;
        }
        for (alias, texture) in &decl.provides {
            if alias.format() != texture.format() {
                return Err(Error::Plan(format!(
                    "pass '{}' provides '{}' as '{}' of another format",
                    decl.name,
                    alias.name(),
                    texture.name()
                )));
            }
            provided.0.insert(*alias, *texture);
        }
    }
    Ok((resolved, provided))
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::TextureFormat::{Depth32Float, Rgba16Float, Rgba8Unorm};

    const DEPTH: Resource = Resource::attachment("depth", Size::Full, Depth32Float);
    const NORMALS: Resource = Resource::attachment("normals", Size::Full, Rgba16Float);
    const HDR: Resource = Resource::storage("hdr", Size::Full, Rgba16Float);
    const COLOR: Resource = Resource::storage("color", Size::Full, Rgba8Unorm);
    const EMISSION: Resource = Resource::attachment("emission", Size::Full, Rgba16Float);
    const RAW: Resource = Resource::storage("raw", Size::Occlusion, Rgba16Float);
    const BLURRED: Resource = Resource::storage("blurred", Size::Occlusion, Rgba16Float);
    const FULL: Resource = Resource::storage("full", Size::Full, Rgba16Float);

    fn decls() -> Vec<PassDecl> {
        vec![
            PassDecl::new("gbuffer").write(DEPTH).write(NORMALS),
            PassDecl::new("lighting").read(DEPTH).read(NORMALS).write(HDR),
            PassDecl::new("tonemap").read(HDR).write(COLOR),
        ]
    }

    /// technique → blur → upsample, and a composite that reads the occlusion.
    fn ao_chain(blur: bool, half_res: bool) -> Vec<PassDecl> {
        vec![
            PassDecl::new("gbuffer").write(DEPTH).write(NORMALS),
            PassDecl::new("ssao").read(DEPTH).write(RAW).provide(OCCLUSION, RAW),
            PassDecl::new("blur").read(OCCLUSION).write(BLURRED).provide(OCCLUSION, BLURRED).disabled_if(!blur, "off"),
            PassDecl::new("upsample")
                .read(OCCLUSION)
                .write(FULL)
                .provide(FINAL_AO, FULL)
                .disabled_if(!half_res, "full"),
            PassDecl::new("composite").read(DEPTH).read(OCCLUSION).write(HDR),
        ]
    }

    #[test]
    fn color_pulls_in_the_whole_chain() {
        let plan = plan(&decls(), &[COLOR], &[]).unwrap();
        assert_eq!(plan.names, vec!["gbuffer", "lighting", "tonemap"]);
        assert!(plan.left_out.is_empty());
    }

    #[test]
    fn a_pass_whose_output_nobody_reads_is_left_out() {
        let plan = plan(&decls(), &[NORMALS], &[]).unwrap();
        assert_eq!(plan.names, vec!["gbuffer"]);
        let names: Vec<_> = plan.left_out.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, vec!["lighting", "tonemap"]);
        assert!(plan.left_out[0].1.contains("hdr"));
    }

    #[test]
    fn disabled_pass_is_left_out_with_its_reason() {
        let mut d = decls();
        d.push(PassDecl::new("mirror").read(COLOR).write(EMISSION).disabled_if(true, "display mode is none"));
        let plan = plan(&d, &[COLOR], &[]).unwrap();
        assert_eq!(plan.left_out, vec![("mirror", "display mode is none".to_string())]);
    }

    #[test]
    fn an_output_nobody_produces_is_an_error() {
        let mut d = decls();
        d[2].disabled = Some("off".into());
        assert!(plan(&d, &[COLOR], &[]).unwrap_err().to_string().contains("color"));
    }

    #[test]
    fn the_final_ao_is_the_last_texture_the_ao_chain_provides() {
        for (blur, half_res, last) in
            [(true, true, FULL), (false, true, FULL), (true, false, BLURRED), (false, false, RAW)]
        {
            let plan = plan(&ao_chain(blur, half_res), &[FINAL_AO], &[]).unwrap();
            assert_eq!(plan.resolve(FINAL_AO), Some(last), "blur {blur} half {half_res}");
            assert!(plan.resources.contains(&last));
            // The composite is not needed for the AO alone; each stage reads the one before.
            assert!(!plan.runs("composite"));
            if half_res {
                let upsample = plan.decls.iter().find(|d| d.name == "upsample").unwrap();
                assert_eq!(upsample.resolve(OCCLUSION), if blur { BLURRED } else { RAW });
            }
        }
    }

    #[test]
    fn a_reader_of_a_named_output_gets_what_the_passes_before_it_provided() {
        let plan = plan(&ao_chain(true, true), &[HDR], &[]).unwrap();
        // The composite reads the blurred occlusion, not the upsampled one after it.
        assert_eq!(plan.names, vec!["gbuffer", "ssao", "blur", "composite"]);
        let composite = plan.decls.last().unwrap();
        assert_eq!(composite.reads, vec![DEPTH, BLURRED]);
    }

    #[test]
    fn a_named_output_nobody_provides_is_an_error() {
        let mut d = ao_chain(true, true);
        d[1].disabled = Some("technique is none".into());
        d[2].disabled = Some("technique is none".into());
        d[3].disabled = Some("technique is none".into());
        // A reader of a named output nobody provides is an error too (the composite
        // unbinds the occlusion when no technique runs).
        assert!(plan(&d, &[DEPTH], &[]).unwrap_err().to_string().contains("'composite' reads 'occlusion'"));
        d.pop();
        assert!(plan(&d, &[FINAL_AO], &[]).unwrap_err().to_string().contains("final-ao"));
        assert!(plan(&d, &[DEPTH], &[]).unwrap().resolve(FINAL_AO).is_none());
    }

    #[test]
    fn an_imported_texture_needs_no_producer_and_is_not_allocated() {
        // The AO engine's chain without a G-buffer pass: the depth comes from the host.
        let chain = &ao_chain(true, true)[1..4];
        assert!(plan(chain, &[FINAL_AO], &[]).unwrap_err().to_string().contains("nothing produces 'depth'"));
        let plan = plan(chain, &[FINAL_AO], &[DEPTH]).unwrap();
        assert_eq!(plan.names, vec!["ssao", "blur", "upsample"]);
        assert!(!plan.resources.contains(&DEPTH), "the graph does not allocate an imported texture");
        assert!(plan.resources.contains(&RAW) && plan.resources.contains(&FULL));
    }

    #[test]
    fn an_unbound_read_is_no_dependency() {
        let d = vec![
            PassDecl::new("gbuffer").write(DEPTH),
            PassDecl::new("shadow").write(EMISSION),
            PassDecl::new("lighting").read(EMISSION).read(DEPTH).write(HDR).unbind(EMISSION),
        ];
        let plan = plan(&d, &[HDR], &[]).unwrap();
        assert!(!plan.runs("shadow"), "{plan}");
    }
}
