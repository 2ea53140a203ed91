//! Headsets as the renderer and the application see them: per-eye size, refresh rate,
//! IPD and fields of view, and the frame budget a refresh gives. The engine needs none of
//! it (a host hands it two eyes).

use vrao_ao::{Error, EyePair, Fov, HeadPose, Result};

/// Default interpupillary distance in metres.
pub const DEFAULT_IPD: f64 = 0.064;
/// The slowest display rate a headset session takes (Hz): Monado's simulated headset
/// runs at 20 Hz; below 10 Hz nothing is a headset any more.
pub const REFRESH_HZ_MIN: f64 = 10.0;
/// The fastest display rate a headset session takes (Hz), well above any headset's 144.
pub const REFRESH_HZ_MAX: f64 = 500.0;

/// A headset's display description: per-eye size, refresh rate and fields of view.
/// Named real headsets are in `xr::profiles` (above this module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadsetProfile {
    /// Short name (`vive`, `index`, …).
    pub name: &'static str,
    /// Per-eye render width in pixels.
    pub width: u32,
    /// Per-eye render height in pixels.
    pub height: u32,
    /// The rate in use; `budget_ms` follows it.
    pub refresh_hz: f64,
    /// The rates the headset can run at (`with_refresh` picks among them).
    pub refresh_rates_hz: &'static [f64],
    /// Interpupillary distance in metres.
    pub ipd: f64,
    /// The left eye's field of view.
    pub fov_left: Fov,
    /// The right eye's field of view.
    pub fov_right: Fov,
}

impl HeadsetProfile {
    /// An HTC Vive-class headset: 1080×1200 per eye at 90 Hz. The frustum is 52° up and
    /// down, 45° towards the nose, and outward as wide as square pixels require.
    /// Size: the Vive's own config, `eye_target_width/height_in_pixels` 1080×1200
    /// (<https://gist.github.com/ChristophHaag/c6235817421f2ce5da839772eff48f40>); 90 Hz: its
    /// hmdq dump (<https://risa2000.github.io/hmdgdb/hmd_cfgs/Vive_Native_R90.html>). The
    /// frustum is an approximation kept as is because earlier measurements used it (the
    /// dump measures 54.4° out, 46.8° nasal, 55.7° up, 55.9° down).
    pub fn vive() -> HeadsetProfile {
        HeadsetProfile::with_size("vive", 1080, 1200)
    }

    /// The Vive-class frustum for another per-eye size, keeping pixels square.
    pub fn with_size(name: &'static str, width: u32, height: u32) -> HeadsetProfile {
        let tan_vertical = 52f64.to_radians().tan();
        let tan_inward = 45f64.to_radians().tan();
        let tan_outward = 2.0 * tan_vertical * width as f64 / height as f64 - tan_inward;
        let left_eye = Fov {
            left: -(tan_outward.atan() as f32),
            right: tan_inward.atan() as f32,
            up: tan_vertical.atan() as f32,
            down: -(tan_vertical.atan() as f32),
        };
        HeadsetProfile {
            name,
            width,
            height,
            refresh_hz: 90.0,
            refresh_rates_hz: &[90.0],
            ipd: DEFAULT_IPD,
            fov_left: left_eye,
            fov_right: left_eye.mirrored(),
        }
    }

    /// The same headset rendered at another per-eye size, keeping its field of view (the
    /// pixels stop being square when the aspect differs from the frustum's).
    pub fn with_render_size(self, width: u32, height: u32) -> HeadsetProfile {
        HeadsetProfile { width, height, ..self }
    }

    /// The same headset at another refresh rate: any rate within
    /// [`REFRESH_HZ_MIN`]..=[`REFRESH_HZ_MAX`] (a runtime may run a headset at a rate its
    /// product sheet does not list, such as Monado's simulated 20 Hz; the simulated
    /// headset takes any of them). A rate outside is `Error::Input` naming the range and
    /// the rates the real headset lists.
    pub fn with_refresh(self, hz: f64) -> Result<HeadsetProfile> {
        // A listed rate parsed from text (e.g. "72.0") is taken exactly as listed.
        if let Some(&rate) = self.refresh_rates_hz.iter().find(|&&r| (r - hz).abs() < 1e-6) {
            return Ok(HeadsetProfile { refresh_hz: rate, ..self });
        }
        if hz.is_finite() && (REFRESH_HZ_MIN..=REFRESH_HZ_MAX).contains(&hz) {
            return Ok(HeadsetProfile { refresh_hz: hz, ..self });
        }
        let rates: Vec<String> = self.refresh_rates_hz.iter().map(|r| r.to_string()).collect();
        Err(Error::input(format!(
            "refresh rate {hz:?} Hz is not within {REFRESH_HZ_MIN}..={REFRESH_HZ_MAX} Hz (headset profile '{}' lists {} Hz)",
            self.name,
            rates.join(", ")
        )))
    }

    /// The frame budget in milliseconds (one refresh period).
    pub fn budget_ms(&self) -> f64 {
        1000.0 / self.refresh_hz
    }

    /// Both eyes of this headset for a head pose: [`EyePair::from_head`] with its IPD and
    /// fields of view.
    pub fn eyes(&self, head: &HeadPose, near: f64) -> EyePair {
        EyePair::from_head(head, self.ipd, self.fov_left, self.fov_right, near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use vrao_ao::plug::DEFAULT_NEAR;

    #[test]
    fn vive_profile_has_square_pixels_and_mirrored_eyes() {
        let p = HeadsetProfile::vive();
        let [l, r, u, d] = p.fov_left.tangents();
        let aspect = (r - l) / (u - d);
        assert!((aspect - 1080.0 / 1200.0).abs() < 1e-6);
        assert_eq!(p.fov_right.left, -p.fov_left.right);
        assert!((p.budget_ms() - 11.111).abs() < 1e-3);
    }
    #[test]
    fn eyes_are_ipd_apart_along_head_right() {
        let head = HeadPose::look_at(DVec3::new(1.0, 1.6, 2.0), DVec3::new(-3.0, 1.0, -1.0)).unwrap();
        let pair = HeadsetProfile::vive().eyes(&head, DEFAULT_NEAR);
        let delta = pair.eyes[1].pose.position - pair.eyes[0].pose.position;
        assert!((delta.length() - DEFAULT_IPD).abs() < 1e-12);
        assert!(delta.dot(head.orientation * DVec3::X) > 0.0, "right eye is to the right");
    }
}
