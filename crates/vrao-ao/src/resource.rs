//! The textures that flow between passes, by name: what a pass reads and writes, and the
//! graph's named outputs. A leaf: the kernels' bindings and the frame graph both name
//! resources.

use crate::frame::DeclareContext;

/// How large a texture is, per layer.
#[derive(Clone, Copy, Debug)]
pub enum Size {
    /// The eyes' full resolution.
    Full,
    /// The occlusion's resolution: half per axis (rounded up) with `--half-res`.
    Occlusion,
    /// Always half per axis (rounded up), whatever `--half-res` says.
    Half,
    /// Width × height × layers worked out by the creating pass (the lights' maps: one
    /// layer per shadowed light, `--shadow-size` a side), from the frame's setup and the
    /// device's largest 2D texture side.
    Computed(fn(&DeclareContext, u32) -> (u32, u32, u32)),
}

/// How a texture is written, which decides its usages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Written {
    /// By render passes, as a colour or depth attachment.
    Attachment,
    /// By compute kernels, as a write-only storage texture.
    Storage,
}

/// What a [`Resource`] is: a texture the graph allocates, or a named output the graph
/// resolves to one.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// A layered texture (one layer per view, or per light for light-space maps).
    Texture {
        /// Its size class.
        size: Size,
        /// How it is written.
        written: Written,
    },
    /// A texture the frame brings from outside the graph (a host application's depth
    /// buffer): never allocated by the graph, and produced by no pass.
    Imported,
    /// A named output: the texture the last enabled pass before the reader provided
    /// under this name; with none, what `fallback` names.
    Alias {
        /// The named output this one falls back to when no pass provides it.
        fallback: Option<&'static Resource>,
    },
}

/// A texture that flows between passes, or a named output of the graph. Two handles are
/// the same resource when their names are: names are unique (the renderer asserts that
/// what it allocates under one name has one format).
#[derive(Clone, Copy, Debug)]
pub struct Resource {
    pub(crate) name: &'static str,
    pub(crate) format: wgpu::TextureFormat,
    pub(crate) kind: Kind,
    /// A target of the AO chain, whose format follows the frame's [`ChainLayout`]
    /// (`format` is its four-channel one).
    pub(crate) chain: bool,
}

/// How the AO chain's targets (the raw occlusion, the denoise's, the accumulation's and
/// the upsampling's) hold a texel this frame. Shaders see both alike through
/// `chain_value` and `chain_texel` (shaders/chain_rgba.wgsl, chain_scalar.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ChainLayout {
    /// rgb light and a AO in `Rgba16Float` (8 bytes): techniques that carry light (SSDO),
    /// and every technique on a device that cannot write `R16Float` storage textures.
    Rgba,
    /// AO alone in `R16Float` (2 bytes): GTAO, SSAO and HBAO where the device writes it.
    Scalar,
}

impl ChainLayout {
    /// The chain targets' texel format.
    pub const fn format(self) -> wgpu::TextureFormat {
        match self {
            ChainLayout::Rgba => wgpu::TextureFormat::Rgba16Float,
            ChainLayout::Scalar => wgpu::TextureFormat::R16Float,
        }
    }

    /// The layout for a technique that does or does not carry light, on a device that
    /// can (`scalar_storage`) or cannot write `R16Float` storage textures.
    pub const fn of(carries_light: bool, scalar_storage: bool) -> ChainLayout {
        if scalar_storage && !carries_light {
            ChainLayout::Scalar
        } else {
            ChainLayout::Rgba
        }
    }
}

impl Resource {
    /// A texture written by compute kernels.
    pub const fn storage(name: &'static str, size: Size, format: wgpu::TextureFormat) -> Resource {
        Resource { name, format, kind: Kind::Texture { size, written: Written::Storage }, chain: false }
    }

    /// A target of the AO chain, written by compute kernels: `Rgba16Float` or `R16Float`
    /// as the frame's [`ChainLayout`] says.
    pub const fn chain_storage(name: &'static str, size: Size) -> Resource {
        Resource {
            name,
            format: ChainLayout::Rgba.format(),
            kind: Kind::Texture { size, written: Written::Storage },
            chain: true,
        }
    }

    /// A texture written by render passes.
    pub const fn attachment(name: &'static str, size: Size, format: wgpu::TextureFormat) -> Resource {
        Resource { name, format, kind: Kind::Texture { size, written: Written::Attachment }, chain: false }
    }

    /// A texture imported from outside the graph each frame; `format` is the format its
    /// readers' layouts assume (depth: any depth format).
    pub const fn imported(name: &'static str, format: wgpu::TextureFormat) -> Resource {
        Resource { name, format, kind: Kind::Imported, chain: false }
    }

    /// A named output whose textures all have `format`, falling back to another named
    /// output when no pass provides it.
    pub const fn alias(
        name: &'static str,
        format: wgpu::TextureFormat,
        fallback: Option<&'static Resource>,
    ) -> Resource {
        Resource { name, format, kind: Kind::Alias { fallback }, chain: false }
    }

    /// A named output of the AO chain: its textures follow the frame's [`ChainLayout`].
    pub const fn chain_alias(name: &'static str, fallback: Option<&'static Resource>) -> Resource {
        Resource { name, format: ChainLayout::Rgba.format(), kind: Kind::Alias { fallback }, chain: true }
    }

    /// The name `--explain`, labels and error messages use (`ao-raw`, `color`, …).
    pub const fn name(self) -> &'static str {
        self.name
    }

    /// The texel format (a chain target's four-channel one: [`Resource::format_in`]).
    pub const fn format(self) -> wgpu::TextureFormat {
        self.format
    }

    /// The texel format in a frame whose chain is laid out as `chain`.
    pub const fn format_in(self, chain: ChainLayout) -> wgpu::TextureFormat {
        if self.chain {
            chain.format()
        } else {
            self.format
        }
    }

    /// Whether this is a target of the AO chain ([`ChainLayout`]).
    pub const fn is_chain(self) -> bool {
        self.chain
    }

    /// Texture or named output.
    pub const fn kind(self) -> Kind {
        self.kind
    }

    /// Whether this is a named output rather than a texture.
    pub fn is_alias(self) -> bool {
        matches!(self.kind, Kind::Alias { .. })
    }
}

impl PartialEq for Resource {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}
impl Eq for Resource {}
impl std::hash::Hash for Resource {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name.hash(state);
    }
}
impl PartialOrd for Resource {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Resource {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.name.cmp(other.name)
    }
}

/// The occlusion at occlusion resolution as the AO chain has it so far: the technique
/// provides its raw AO, temporal accumulation and the denoise each replace it. Layout as
/// the techniques write it: rgb = SSDO's gathered irradiance, a = AO.
pub const OCCLUSION: Resource = Resource::chain_alias("occlusion", None);

/// Each pixel's motion since the previous frame, as `MOTION` (passes/inputs.rs)
/// lays it out: the G-buffer's in a scene that moves, or the motion vectors a host hands
/// the AO engine. Temporal accumulation reads it.
pub const PIXEL_MOTION: Resource = Resource::alias("pixel-motion", wgpu::TextureFormat::Rgba16Float, None);

/// The final AO at full resolution: the upsampled occlusion, or [`OCCLUSION`] itself
/// when the occlusion runs at full resolution. What the outputs, the bench and the
/// window's buffer view read.
pub const FINAL_AO: Resource = Resource::chain_alias("final-ao", Some(&OCCLUSION));
