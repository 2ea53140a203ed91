//! The technique table: every occlusion technique's name, kind, composite mode, sample
//! pattern, foveation rule and pass, in one place. Adding a technique is its folder under
//! `src/passes/` (its Rust and WGSL), its variant below and its line in [`TECHNIQUES`];
//! the chain (`passes::ao_chain`), the uniforms (`gpu::uniforms`), the
//! denoise and the composite read what they need from the entry.

use crate::error::{Error, Result};

/// The occlusion technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Technique {
    /// No occlusion pass: the ambient term is unoccluded.
    None,
    /// Normal-oriented hemisphere SSAO (Belonogov 2018 §3.2, the Czech SSDO thesis ch. 3).
    Ssao,
    /// Horizon-based AO, directions × steps ray-marched in depth (Belonogov 2018 §3.3).
    Hbao,
    /// Ground-truth AO over screen-space slices with a visibility bitmask and a thickness
    /// (Jimenez et al. 2016, Therrien et al. 2023). The default: the most accurate per
    /// millisecond.
    #[default]
    Gtao,
    /// Screen-space directional occlusion of the environment (Ritschel et al. 2009 eq. 1)
    /// on GTAO's slices and visibility bitmask: GTAO's occlusion, and the environment
    /// light through the unoccluded sectors in rgb.
    Ssdo,
    /// [`Technique::Ssdo`] plus one bounce of direct light from the senders of the newly
    /// covered sectors (Ritschel et al. 2009 eq. 2 on sectors, Therrien et al. 2023).
    SsdoBounce,
    /// The seeds' point-sampled SSDO (Ritschel et al. 2009 eq. 1, a hemisphere of sample
    /// points), kept as a measured baseline; vrao's renderer supplies its pass (the engine
    /// has none). Only with the `measurement` feature, not for hosts.
    #[cfg(feature = "measurement")]
    SsdoPoints,
    /// `SsdoPoints` plus the seeds' point-sampled bounce (eq. 2). Only with the
    /// `measurement` feature, not for hosts.
    #[cfg(feature = "measurement")]
    SsdoPointsBounce,
    /// Benchmark baseline, not an occlusion: SSAO's depth taps with no arithmetic. Only
    /// with the `measurement` feature (vrao's bench), not for hosts.
    #[cfg(feature = "measurement")]
    FetchOnly,
}

/// What kind of estimate a technique makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TechniqueKind {
    /// No estimate (the ambient is unoccluded).
    Off,
    /// Depth tests of a kernel of points in the normal's hemisphere.
    Hemisphere,
    /// Horizons or sectors found by marching depth along screen-space directions.
    HorizonMarch,
    /// Occlusion and the light that arrives through the unblocked directions, in colour,
    /// from the frame's environment and direct light (SSDO).
    LightGathering,
    /// A cost baseline that estimates nothing.
    Baseline,
}

/// How the composite applies the technique's output (`ao.technique` in the shaders; the
/// constants `COMPOSITE_*` of common.wgsl hold the same numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum CompositeMode {
    /// Unoccluded ambient.
    Unoccluded = 0,
    /// The ambient times the AO in alpha.
    ScalarAo = 1,
    /// The gathered light in rgb replaces the ambient (SSDO).
    Directional = 2,
}

/// The pattern a technique's samples follow, and how it changes frame to frame with
/// temporal accumulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplePattern {
    /// None.
    Nothing,
    /// The Halton hemisphere kernel, cosine-weighted; temporal accumulation gives each
    /// frame its own part of a longer kernel.
    HemisphereCosine,
    /// The Halton hemisphere kernel, uniform (the technique weighs each direction by its
    /// cosine itself); parts per frame as above.
    HemisphereUniform,
    /// Screen-space directions; temporal accumulation turns them by the golden angle.
    Directions,
}

/// What fixed foveation thins towards the image's edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoveationRule {
    /// Nothing (no per-pixel work to thin).
    Unaffected,
    /// The hemisphere kernel's sample count.
    Samples,
    /// The march's directions (slices), then its steps.
    DirectionsThenSteps,
}

/// One technique's line of the table.
#[derive(Clone, Copy, Debug)]
pub struct TechniqueEntry {
    /// The technique.
    pub technique: Technique,
    /// Its command-line name, also its pass's name and the name in files and reports.
    pub name: &'static str,
    /// What the command line's help says of it after its name ("": nothing);
    /// [`Technique::help_list`].
    pub help: &'static str,
    /// What kind of estimate it makes.
    pub kind: TechniqueKind,
    /// How the composite applies it.
    pub composite: CompositeMode,
    /// Its samples' pattern (which kernel the frame's uniforms carry).
    pub samples: SamplePattern,
    /// What foveation thins.
    pub foveation: FoveationRule,
    /// Whether the engine's chain has a pass for it (not `none`, nor a light-gathering
    /// technique whose pass a renderer supplies): the chain (`passes::ao_chain`) makes it.
    pub engine_pass: bool,
}

/// Every technique, in the order the CLI and the bench list them.
pub(crate) const TECHNIQUES: [TechniqueEntry; OCCLUSION_TECHNIQUES.len() + BASELINES.len()] = {
    let mut all = [OCCLUSION_TECHNIQUES[0]; OCCLUSION_TECHNIQUES.len() + BASELINES.len()];
    let mut i = 0;
    while i < all.len() {
        all[i] = if i < OCCLUSION_TECHNIQUES.len() {
            OCCLUSION_TECHNIQUES[i]
        } else {
            BASELINES[i - OCCLUSION_TECHNIQUES.len()]
        };
        i += 1;
    }
    all
};

/// The techniques that estimate something (and none).
const OCCLUSION_TECHNIQUES: [TechniqueEntry; 6] = [
    TechniqueEntry {
        technique: Technique::None,
        name: "none",
        help: "",
        kind: TechniqueKind::Off,
        composite: CompositeMode::Unoccluded,
        samples: SamplePattern::Nothing,
        foveation: FoveationRule::Unaffected,
        engine_pass: false,
    },
    TechniqueEntry {
        technique: Technique::Ssao,
        name: "ssao",
        help: "",
        kind: TechniqueKind::Hemisphere,
        composite: CompositeMode::ScalarAo,
        samples: SamplePattern::HemisphereCosine,
        foveation: FoveationRule::Samples,
        engine_pass: true,
    },
    TechniqueEntry {
        technique: Technique::Hbao,
        name: "hbao",
        help: "",
        kind: TechniqueKind::HorizonMarch,
        composite: CompositeMode::ScalarAo,
        samples: SamplePattern::Directions,
        foveation: FoveationRule::DirectionsThenSteps,
        engine_pass: true,
    },
    TechniqueEntry {
        technique: Technique::Gtao,
        name: "gtao",
        help: "the most accurate per millisecond",
        kind: TechniqueKind::HorizonMarch,
        composite: CompositeMode::ScalarAo,
        samples: SamplePattern::Directions,
        foveation: FoveationRule::DirectionsThenSteps,
        engine_pass: true,
    },
    TechniqueEntry {
        technique: Technique::Ssdo,
        name: "ssdo",
        help: "GTAO's march gathering the environment",
        kind: TechniqueKind::LightGathering,
        composite: CompositeMode::Directional,
        samples: SamplePattern::Directions,
        foveation: FoveationRule::DirectionsThenSteps,
        engine_pass: true,
    },
    TechniqueEntry {
        technique: Technique::SsdoBounce,
        name: "ssdo-bounce",
        help: "ssdo and one bounce of direct light",
        kind: TechniqueKind::LightGathering,
        composite: CompositeMode::Directional,
        samples: SamplePattern::Directions,
        foveation: FoveationRule::DirectionsThenSteps,
        engine_pass: true,
    },
];

/// What vrao's measurements compare against, with the `measurement` feature only: the
/// seeds' point-sampled SSDO (its pass is the renderer's) and the bench's cost baseline.
#[cfg(feature = "measurement")]
const BASELINES: [TechniqueEntry; 3] = [
    TechniqueEntry {
        technique: Technique::SsdoPoints,
        name: "ssdo-points",
        help: "the seeds' point-sampled SSDO, a baseline",
        kind: TechniqueKind::LightGathering,
        composite: CompositeMode::Directional,
        samples: SamplePattern::HemisphereUniform,
        foveation: FoveationRule::Samples,
        engine_pass: false,
    },
    TechniqueEntry {
        technique: Technique::SsdoPointsBounce,
        name: "ssdo-points-bounce",
        help: "ssdo-points and its point-sampled bounce",
        kind: TechniqueKind::LightGathering,
        composite: CompositeMode::Directional,
        samples: SamplePattern::HemisphereUniform,
        foveation: FoveationRule::Samples,
        engine_pass: false,
    },
    TechniqueEntry {
        technique: Technique::FetchOnly,
        name: "fetch-only",
        help: "the benchmark baseline with SSAO's depth taps and no occlusion arithmetic",
        kind: TechniqueKind::Baseline,
        composite: CompositeMode::ScalarAo,
        samples: SamplePattern::HemisphereCosine,
        foveation: FoveationRule::Samples,
        engine_pass: true,
    },
];

/// No baselines without the `measurement` feature.
#[cfg(not(feature = "measurement"))]
const BASELINES: [TechniqueEntry; 0] = [];

impl Technique {
    /// Whether the technique reads a second depth layer when the settings ask for two
    /// (`AoSettings::layers`): the marches on GTAO's bitmask (GTAO, SSDO), whose samples
    /// then block the span between the layers instead of a slab.
    pub fn reads_second_layer(self) -> bool {
        matches!(self, Technique::Gtao | Technique::Ssdo | Technique::SsdoBounce)
    }

    /// Every technique, in the order the CLI and the bench list them (the table's).
    pub const ALL: [Technique; TECHNIQUES.len()] = {
        let mut all = [Technique::None; TECHNIQUES.len()];
        let mut i = 0;
        while i < TECHNIQUES.len() {
            all[i] = TECHNIQUES[i].technique;
            i += 1;
        }
        all
    };

    /// The technique's line of `TECHNIQUES`.
    pub fn entry(self) -> &'static TechniqueEntry {
        TECHNIQUES.iter().find(|e| e.technique == self).expect("every technique has a line (checked by a test)")
    }

    /// Every technique's name in `TECHNIQUES`' order with its help in brackets (the
    /// default's marked), the last after "or": the list the command line's help shows.
    pub fn help_list() -> String {
        let items: Vec<String> = TECHNIQUES
            .iter()
            .map(|e| {
                let default = e.technique == Technique::default();
                match (default, e.help) {
                    (false, "") => e.name.to_string(),
                    (false, help) => format!("{} ({help})", e.name),
                    (true, "") => format!("{} (the default)", e.name),
                    (true, help) => format!("{} (the default: {help})", e.name),
                }
            })
            .collect();
        match items.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }

    /// The technique's command-line name (`ssao`, `hbao`, …), also used in file names and reports.
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// True for the techniques whose occlusion targets carry gathered light in rgb
    /// (`LightGathering`); the others write AO in alpha alone (rgb 0),
    /// so the denoise filters alpha alone for them.
    pub fn carries_light(self) -> bool {
        self.entry().kind == TechniqueKind::LightGathering
    }

    /// Whether the technique gathers a bounce of direct light (`ssdo-bounce`,
    /// `ssdo-points-bounce`).
    pub fn gathers_bounce(self) -> bool {
        self.without_bounce() != self
    }

    /// The same technique without its bounce (itself when it has none): what the bench
    /// subtracts to see the bounce alone.
    pub fn without_bounce(self) -> Technique {
        match self {
            Technique::SsdoBounce => Technique::Ssdo,
            #[cfg(feature = "measurement")]
            Technique::SsdoPointsBounce => Technique::SsdoPoints,
            other => other,
        }
    }

    /// Whether vrao's renderer supplies the technique's pass (the point-sampled SSDO of
    /// the `measurement` feature, which the AO engine does not run); never without it.
    pub fn renderer_only(self) -> bool {
        !self.entry().engine_pass && self.entry().kind == TechniqueKind::LightGathering
    }

    /// Every technique, in the order the CLI and the bench list them ([`Technique::ALL`]).
    pub fn all() -> &'static [Technique] {
        &Technique::ALL
    }

    /// The techniques that estimate occlusion (neither `none` nor the fetch-only
    /// baseline), the default first, then in [`Technique::all`]'s order: what `vrao bench`
    /// sweeps unless told otherwise.
    pub fn estimators() -> Vec<Technique> {
        let default = Technique::default();
        let estimates = |t: &Technique| !matches!(t.entry().kind, TechniqueKind::Off | TechniqueKind::Baseline);
        let others = Technique::all().iter().copied().filter(|&t| t != default && estimates(&t));
        std::iter::once(default).chain(others).collect()
    }
}

/// Bench files name their techniques, and the governor and `vrao budget --fit` read them
/// back; the names are the command line's ([`Technique::name`]).
impl std::str::FromStr for Technique {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Technique::ALL.into_iter().find(|t| t.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Technique::all().iter().map(|t| t.name()).collect();
            Error::input(format!("unknown technique '{s}' (expected one of {})", names.join(", ")))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_technique_has_exactly_one_line_and_distinct_names() {
        for (i, entry) in TECHNIQUES.iter().enumerate() {
            let lines = TECHNIQUES.iter().filter(|e| e.technique == entry.technique).count();
            assert_eq!(lines, 1, "{:?} has {lines} lines", entry.technique);
            assert!(TECHNIQUES[..i].iter().all(|e| e.name != entry.name), "{} is named twice", entry.name);
        }
        // Every variant has a line: a match without a wildcard fails to compile when a
        // variant is added, and the variant must then be given a line here.
        for t in [
            Technique::None,
            Technique::Ssao,
            Technique::Hbao,
            Technique::Gtao,
            Technique::Ssdo,
            Technique::SsdoBounce,
            #[cfg(feature = "measurement")]
            Technique::SsdoPoints,
            #[cfg(feature = "measurement")]
            Technique::SsdoPointsBounce,
            #[cfg(feature = "measurement")]
            Technique::FetchOnly,
        ] {
            match t {
                Technique::None
                | Technique::Ssao
                | Technique::Hbao
                | Technique::Gtao
                | Technique::Ssdo
                | Technique::SsdoBounce => assert!(Technique::ALL.contains(&t), "{t:?} has no line"),
                #[cfg(feature = "measurement")]
                Technique::SsdoPoints | Technique::SsdoPointsBounce | Technique::FetchOnly => {
                    assert!(Technique::ALL.contains(&t), "{t:?} has no line")
                }
            }
        }
    }

    #[test]
    fn the_help_list_names_every_technique_from_the_table() {
        let list = Technique::help_list();
        for e in &TECHNIQUES {
            assert!(list.contains(e.name), "{} missing from {list}", e.name);
        }
        assert!(list.starts_with("none, ssao, hbao, gtao (the default: the most accurate"), "{list}");
        // The table's last line (fetch-only with the measurement feature).
        let last = TECHNIQUES.last().unwrap();
        assert!(list.ends_with(&format!(" or {} ({})", last.name, last.help)), "{list}");
    }

    #[test]
    fn the_entries_fields_agree_with_each_other() {
        for e in &TECHNIQUES {
            let off = e.kind == TechniqueKind::Off;
            assert_eq!(off, e.composite == CompositeMode::Unoccluded, "{}", e.name);
            assert_eq!(off, e.samples == SamplePattern::Nothing, "{}", e.name);
            assert_eq!(
                e.kind == TechniqueKind::LightGathering,
                e.composite == CompositeMode::Directional,
                "{}",
                e.name
            );
            // The engine builds a pass for every technique but `none` and the point-sampled
            // SSDO, which a renderer supplies.
            let engine_pass = e.kind != TechniqueKind::Off && !e.name.starts_with("ssdo-points");
            assert_eq!(e.engine_pass, engine_pass, "{}", e.name);
            let marches =
                e.kind == TechniqueKind::HorizonMarch || (e.kind == TechniqueKind::LightGathering && engine_pass);
            assert_eq!(marches, e.samples == SamplePattern::Directions, "{}", e.name);
            assert_eq!(marches, e.foveation == FoveationRule::DirectionsThenSteps, "{}", e.name);
        }
    }

    #[test]
    fn the_composite_codes_are_the_shaders() {
        let common = include_str!("../shaders/common.wgsl");
        for (name, mode) in [
            ("COMPOSITE_UNOCCLUDED", CompositeMode::Unoccluded),
            ("COMPOSITE_SCALAR_AO", CompositeMode::ScalarAo),
            ("COMPOSITE_DIRECTIONAL", CompositeMode::Directional),
        ] {
            let line = format!("const {name}: u32 = {}u;", mode as u32);
            assert!(common.contains(&line), "common.wgsl lacks `{line}`");
        }
    }
}
