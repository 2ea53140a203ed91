//! Render settings, validated once so passes can trust them.

use crate::error::{Error, Result};
use crate::stereo::{HeadsetProfile, DEFAULT_NEAR};

/// How the G-buffer reaches both eye layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StereoMode {
    /// Multiview when the adapter has it, one pass per eye otherwise.
    #[default]
    Auto,
    /// One render pass writes both layers (`view_index` selects the eye).
    Multiview,
    /// One render pass per eye layer.
    Multipass,
}

impl std::str::FromStr for StereoMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(StereoMode::Auto),
            "multiview" => Ok(StereoMode::Multiview),
            "multipass" => Ok(StereoMode::Multipass),
            other => Err(format!("unknown stereo mode '{other}' (expected auto, multiview or multipass)")),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The headset's per-eye size, refresh rate, IPD and fields of view.
    pub profile: HeadsetProfile,
    pub stereo: StereoMode,
    /// Near plane in metres (the far plane is at infinity).
    pub near: f64,
    /// Linear exposure applied before tone mapping.
    pub exposure: f32,
    /// Reinhard's L_white: the smallest (exposed) luminance mapped to white.
    pub white_point: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            profile: HeadsetProfile::vive(),
            stereo: StereoMode::Auto,
            near: DEFAULT_NEAR,
            exposure: 1.0,
            white_point: 4.0,
        }
    }
}

impl Settings {
    /// Checks every value; the error names the setting and the value.
    pub fn validate(&self) -> Result<()> {
        let p = &self.profile;
        if p.width == 0 || p.height == 0 || p.width > 8192 || p.height > 8192 {
            return Err(Error::input(format!("eye size {}x{} is not within 1..=8192", p.width, p.height)));
        }
        if !(p.ipd.is_finite() && (0.0..=1.0).contains(&p.ipd)) {
            return Err(Error::input(format!("ipd {} m is not within 0..=1 m", p.ipd)));
        }
        for fov in [p.fov_left, p.fov_right] {
            fov.validate().map_err(Error::input)?;
        }
        if !(self.near.is_finite() && self.near > 0.0) {
            return Err(Error::input(format!("near plane {} m must be a positive finite number", self.near)));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(Error::input(format!("exposure {} must be a positive finite number", self.exposure)));
        }
        if !(self.white_point.is_finite() && self.white_point > 0.0) {
            return Err(Error::input(format!("white point {} must be a positive finite number", self.white_point)));
        }
        Ok(())
    }
}
