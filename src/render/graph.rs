//! The frame graph. Each pass declares what it reads and writes, and whether the scene
//! and settings let it exist at all. Given the outputs a frame must produce, the graph
//! keeps exactly the passes those outputs depend on and says why every other pass was
//! left out. Passes are declared in execution order, so the kept ones run in that order.

use std::collections::BTreeSet;
use std::fmt;

/// A resource that flows between passes (a layered texture, one layer per view).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Resource {
    /// Reversed-Z depth, `Depth32Float`.
    Depth,
    /// Depth peeling's second layer (SSDO's quality mode): the nearest surface behind
    /// `Depth`, reversed-Z `Depth32Float`, 0 where nothing lies behind.
    DepthLayer2,
    /// View-space unit normals, `Rgba16Float` (w unused).
    Normals,
    /// Diffuse albedo, `Rgba8UnormSrgb` (reads back linear).
    Albedo,
    /// Emitted radiance, `Rgba16Float`.
    Emission,
    /// Outgoing direct radiance (lights and emission) and the view distance, packed in
    /// `Rg32Uint` (common.wgsl `pack_direct`: distance f32, radiance RGB9E5): the
    /// composite's base, and depth test plus sender radiance of SSDO's bounce in a
    /// single fetch.
    Direct,
    /// Occlusion as computed (at AO resolution), `Rgba16Float`: rgb = SSDO's gathered
    /// irradiance (environment through unblocked directions plus the bounce), a = AO.
    AoRaw,
    /// Normal (xyz) and view distance (w, 0 on the sky) at each occlusion pixel,
    /// `Rgba32Float`, written by the technique so the blur and upsample need one fetch
    /// per tap instead of depth, normal and a reconstruction.
    AoGeometry,
    /// Horizontally blurred occlusion (first half of the separable bilateral blur).
    AoBlurH,
    /// Bilaterally blurred occlusion, at AO resolution.
    AoBlurred,
    /// Occlusion upsampled from half to full resolution (3×3 joint bilateral).
    AoFull,
    /// Lit scene radiance before tone mapping, `Rgba16Float`.
    Hdr,
    /// Tone-mapped, sRGB-encoded eye colour, `Rgba8Unorm`.
    Color,
    /// Occlusion accumulated over frames by reverse reprojection (temporal pass), at AO
    /// resolution, `Rgba16Float`, laid out as `AoRaw`.
    AoAccumulated,
    /// The temporal history, ping-ponged between frames: accumulated value (`Rgba16Float`)
    /// and world position relative to the scene anchor with the accumulated frame count
    /// in w (`Rgba32Float`). These persist from one frame to the next.
    HistoryValueA,
    /// The other half of `HistoryValueA`'s ping-pong pair.
    HistoryValueB,
    /// Accumulated world position and frame count, one half of a ping-pong pair.
    HistoryPositionA,
    /// The other half of `HistoryPositionA`'s ping-pong pair.
    HistoryPositionB,
    /// Light-space depth of each shadowed directional light (one layer per light, square,
    /// `--shadow-size` texels a side), `Depth32Float`, 0 nearest the light, 1 = nothing.
    ShadowMap,
    /// Reflective shadow map: light-view normal per light-space texel, `Rgba16Float`.
    RsmNormal,
    /// Reflective shadow map: flux density (albedo × light irradiance) per texel, `Rgba16Float`.
    RsmFlux,
    /// One-bounce irradiance gathered from the reflective shadow maps, half resolution
    /// per axis, `Rgba16Float` (rgb).
    RsmIndirect,
    /// Normal (xyz) and view distance (w) at each `RsmIndirect` pixel, `Rgba32Float`, for
    /// the composite's joint bilateral upsampling.
    RsmGeometry,
}

impl Resource {
    /// Resources that live at the occlusion resolution (half per axis with `--half-res`).
    pub fn at_ao_resolution(self) -> bool {
        matches!(
            self,
            Resource::AoRaw
                | Resource::AoGeometry
                | Resource::AoBlurH
                | Resource::AoBlurred
                | Resource::AoAccumulated
                | Resource::HistoryValueA
                | Resource::HistoryValueB
                | Resource::HistoryPositionA
                | Resource::HistoryPositionB
        )
    }

    /// Written by render passes (attachments) rather than by compute kernels.
    pub fn is_attachment(self) -> bool {
        matches!(
            self,
            Resource::Depth | Resource::DepthLayer2 | Resource::Normals | Resource::Albedo | Resource::Emission
        ) || self.in_light_space()
    }

    /// Resources of the directional lights' maps (sized by the shadow settings, one
    /// layer per shadowed light) rather than of the eyes.
    pub fn in_light_space(self) -> bool {
        matches!(self, Resource::ShadowMap | Resource::RsmNormal | Resource::RsmFlux)
    }

    /// Resources always at half resolution per axis (rounded up), whatever `--half-res` says.
    pub fn at_half_resolution(self) -> bool {
        matches!(self, Resource::RsmIndirect | Resource::RsmGeometry)
    }

    /// The name `--explain` and error messages use (`ao-raw`, `color`, …).
    pub fn name(self) -> &'static str {
        match self {
            Resource::Depth => "depth",
            Resource::DepthLayer2 => "depth-layer-2",
            Resource::Normals => "normals",
            Resource::Albedo => "albedo",
            Resource::Emission => "emission",
            Resource::Direct => "direct",
            Resource::AoRaw => "ao-raw",
            Resource::AoGeometry => "ao-geometry",
            Resource::AoBlurH => "ao-blur-h",
            Resource::AoBlurred => "ao-blurred",
            Resource::AoFull => "ao-full",
            Resource::Hdr => "hdr",
            Resource::Color => "color",
            Resource::AoAccumulated => "ao-accumulated",
            Resource::HistoryValueA => "history-value-a",
            Resource::HistoryValueB => "history-value-b",
            Resource::HistoryPositionA => "history-position-a",
            Resource::HistoryPositionB => "history-position-b",
            Resource::ShadowMap => "shadow-map",
            Resource::RsmNormal => "rsm-normal",
            Resource::RsmFlux => "rsm-flux",
            Resource::RsmIndirect => "rsm-indirect",
            Resource::RsmGeometry => "rsm-geometry",
        }
    }

    /// The texture format the resource is allocated with.
    pub fn format(self) -> wgpu::TextureFormat {
        match self {
            Resource::Depth | Resource::DepthLayer2 => wgpu::TextureFormat::Depth32Float,
            Resource::Normals
            | Resource::Emission
            | Resource::AoRaw
            | Resource::AoBlurH
            | Resource::AoBlurred
            | Resource::AoFull
            | Resource::AoAccumulated
            | Resource::HistoryValueA
            | Resource::HistoryValueB
            | Resource::Hdr => wgpu::TextureFormat::Rgba16Float,
            Resource::Albedo => wgpu::TextureFormat::Rgba8UnormSrgb,
            Resource::AoGeometry | Resource::HistoryPositionA | Resource::HistoryPositionB => {
                wgpu::TextureFormat::Rgba32Float
            }
            Resource::Color => wgpu::TextureFormat::Rgba8Unorm,
            Resource::ShadowMap => wgpu::TextureFormat::Depth32Float,
            Resource::RsmNormal | Resource::RsmFlux | Resource::RsmIndirect => wgpu::TextureFormat::Rgba16Float,
            Resource::RsmGeometry => wgpu::TextureFormat::Rgba32Float,
            Resource::Direct => wgpu::TextureFormat::Rg32Uint,
        }
    }
}

/// What a pass declares for one frame.
#[derive(Clone, Debug)]
pub struct PassDecl {
    /// The pass's name, as `--explain` and the GPU timings show it.
    pub name: &'static str,
    /// Resources the pass reads.
    pub reads: Vec<Resource>,
    /// Resources the pass writes.
    pub writes: Vec<Resource>,
    /// `Some(reason)` when the scene or settings rule the pass out for this frame.
    pub disabled: Option<String>,
    /// What `--explain` should add about work left out inside a running pass.
    pub note: Option<String>,
}

impl PassDecl {
    /// A pass that reads and writes nothing yet.
    pub fn new(name: &'static str) -> PassDecl {
        PassDecl { name, reads: Vec::new(), writes: Vec::new(), disabled: None, note: None }
    }
    /// Adds a resource the pass reads.
    pub fn read(mut self, r: Resource) -> Self {
        self.reads.push(r);
        self
    }
    /// Adds a resource the pass writes.
    pub fn write(mut self, r: Resource) -> Self {
        self.writes.push(r);
        self
    }
    /// Adds what `--explain` says about work left out inside the pass.
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.note = Some(note.into());
        self
    }
    /// Rules the pass out when `condition` holds, with `reason` shown by `--explain`.
    pub fn disabled_if(mut self, condition: bool, reason: impl Into<String>) -> Self {
        if condition && self.disabled.is_none() {
            self.disabled = Some(reason.into());
        }
        self
    }
}

/// The passes one frame runs and the ones it leaves out.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Indices into the declarations, in execution order.
    pub run: Vec<usize>,
    /// Names of the passes that run, in execution order.
    pub names: Vec<&'static str>,
    /// Notes of running passes (work they leave out internally).
    pub notes: Vec<(&'static str, String)>,
    /// (pass, reason) for every pass that does not run.
    pub left_out: Vec<(&'static str, String)>,
    /// Every resource a running pass reads or writes (what the frame must allocate).
    pub resources: BTreeSet<Resource>,
}

impl Plan {
    /// Whether the pass of this name runs.
    pub fn runs(&self, name: &str) -> bool {
        self.names.contains(&name)
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

/// Keeps the passes `outputs` depend on. An output that no enabled pass produces is an
/// error naming it (a renderer bug or an impossible request, never silently dropped).
pub fn plan(decls: &[PassDecl], outputs: &[Resource]) -> Result<Plan, String> {
    let mut needed: BTreeSet<Resource> = outputs.iter().copied().collect();
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
        let produced = decls.iter().zip(&keep).any(|(d, k)| *k && d.writes.contains(r));
        if !produced {
            return Err(format!("nothing produces '{}' for this frame", r.name()));
        }
    }
    let mut plan =
        Plan { run: Vec::new(), names: Vec::new(), notes: Vec::new(), left_out: Vec::new(), resources: needed };
    for (i, decl) in decls.iter().enumerate() {
        if keep[i] {
            plan.resources.extend(decl.writes.iter().copied());
            plan.run.push(i);
            plan.names.push(decl.name);
            if let Some(note) = &decl.note {
                plan.notes.push((decl.name, note.clone()));
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use Resource::*;

    fn decls() -> Vec<PassDecl> {
        vec![
            PassDecl::new("gbuffer").write(Depth).write(Normals).write(Albedo),
            PassDecl::new("lighting").read(Depth).read(Normals).read(Albedo).write(Hdr),
            PassDecl::new("tonemap").read(Hdr).write(Color),
        ]
    }

    #[test]
    fn color_pulls_in_the_whole_chain() {
        let plan = plan(&decls(), &[Color]).unwrap();
        assert_eq!(plan.names, vec!["gbuffer", "lighting", "tonemap"]);
        assert!(plan.left_out.is_empty());
    }

    #[test]
    fn a_pass_whose_output_nobody_reads_is_left_out() {
        let plan = plan(&decls(), &[Normals]).unwrap();
        assert_eq!(plan.names, vec!["gbuffer"]);
        let names: Vec<_> = plan.left_out.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, vec!["lighting", "tonemap"]);
        assert!(plan.left_out[0].1.contains("hdr"));
    }

    #[test]
    fn disabled_pass_is_left_out_with_its_reason() {
        let mut d = decls();
        d.push(PassDecl::new("mirror").read(Color).write(Emission).disabled_if(true, "display mode is none"));
        let plan = plan(&d, &[Color]).unwrap();
        assert_eq!(plan.left_out, vec![("mirror", "display mode is none".to_string())]);
    }

    #[test]
    fn an_output_nobody_produces_is_an_error() {
        let mut d = decls();
        d[2].disabled = Some("off".into());
        assert!(plan(&d, &[Color]).unwrap_err().contains("color"));
    }
}
