//! What the desktop window shows of each eye: the eye images or a buffer behind them.

use vrao_ao::plug::{Resource, AO_RAW, DEPTH, FINAL_AO, NORMALS};
use vrao_ao::Technique;
use vrao_render::settings::Settings;

/// What the desktop window shows of each eye (`vrao run --show`, the panel's "show"):
/// the eye images, or one of the buffers behind them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BufferView {
    /// The eye images (or, in the mirror, what the headset's compositor shows).
    #[default]
    Eyes,
    /// The occlusion the composite applies (blurred, upsampled or accumulated), as grey.
    #[value(name = "ao")]
    FinalAo,
    /// The occlusion as the technique computed it, before any filter, as grey.
    RawAo,
    /// Reversed-Z depth as log-distance: near white, far dark, sky black.
    Depth,
    /// View-space normals, xyz mapped from [-1, 1] to colour.
    Normals,
}

impl BufferView {
    /// The renderer's resource that holds this view under `settings` (the final AO is
    /// the graph's named output); `None` for the eye images and for AO when no technique
    /// runs.
    pub fn resource(self, settings: &Settings) -> Option<Resource> {
        let any_ao = settings.ao.technique != Technique::None;
        match self {
            BufferView::Eyes => None,
            BufferView::FinalAo => any_ao.then_some(FINAL_AO),
            BufferView::RawAo => any_ao.then_some(AO_RAW),
            BufferView::Depth => Some(DEPTH),
            BufferView::Normals => Some(NORMALS),
        }
    }

    /// The view's name as the command line and the panel spell it (`ao`, `raw-ao`, …).
    pub fn name(self) -> String {
        clap::ValueEnum::to_possible_value(&self).map_or_else(|| format!("{self:?}"), |v| v.get_name().to_string())
    }
}
