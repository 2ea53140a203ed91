//! Scripted head motion for the simulated headset: offsets on top of the scene's head
//! pose (or its path), as a function of time.

use glam::{DQuat, DVec3};
use std::f64::consts::TAU;
use vrao_ao::HeadPose;
use vrao_render::scene::HeadPath;

/// Head motion the simulated headset adds to the scene's pose, for testing stereo and reprojection under movement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "app", derive(clap::ValueEnum))]
pub enum HeadMotion {
    /// The scene's head pose (or its scripted path) as is.
    #[default]
    Static,
    /// Yaw swinging ±30° about the vertical, a 4 s period: a user looking around.
    YawSweep,
    /// Walking a figure eight 1 m wide and 0.5 m deep in 8 s, facing the scene's way.
    FigureEight,
    /// Rolling the head ±20° about the view axis in 3 s.
    HeadRoll,
}

impl HeadMotion {
    /// Every motion, in the order the CLI lists them.
    pub const ALL: [HeadMotion; 4] =
        [HeadMotion::Static, HeadMotion::YawSweep, HeadMotion::FigureEight, HeadMotion::HeadRoll];

    /// The motion's `--motion` name.
    pub fn name(self) -> &'static str {
        match self {
            HeadMotion::Static => "static",
            HeadMotion::YawSweep => "yaw-sweep",
            HeadMotion::FigureEight => "figure-eight",
            HeadMotion::HeadRoll => "head-roll",
        }
    }

    /// The head pose at time `t` seconds: the scene's path at `t` with this motion applied
    /// in the head's own frame.
    pub fn pose_at(self, path: &HeadPath, t: f64) -> HeadPose {
        let base = path.pose_at(t).sanitized();
        let (offset, turn) = match self {
            HeadMotion::Static => (DVec3::ZERO, DQuat::IDENTITY),
            HeadMotion::YawSweep => (DVec3::ZERO, DQuat::from_rotation_y(30f64.to_radians() * (TAU * t / 4.0).sin())),
            HeadMotion::FigureEight => {
                let w = TAU * t / 8.0;
                (DVec3::new(0.5 * w.sin(), 0.0, 0.25 * (2.0 * w).sin()), DQuat::IDENTITY)
            }
            HeadMotion::HeadRoll => (DVec3::ZERO, DQuat::from_rotation_z(20f64.to_radians() * (TAU * t / 3.0).sin())),
        };
        // Yaw turns about world up; roll and walking happen in the head's frame.
        let (position, orientation) = match self {
            HeadMotion::YawSweep => (base.position, turn * base.orientation),
            _ => (base.position + base.orientation * offset, base.orientation * turn),
        };
        HeadPose { position, orientation: orientation.normalize() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> HeadPath {
        HeadPath::fixed(HeadPose::look_at(DVec3::new(0.0, 1.6, 2.0), DVec3::new(0.0, 1.6, 0.0)).unwrap())
    }

    fn angle_between(a: DQuat, b: DQuat) -> f64 {
        a.angle_between(b).to_degrees()
    }

    #[test]
    fn static_motion_is_the_scene_pose_at_every_time() {
        let p = path();
        for t in [0.0, 0.7, 5.0] {
            assert_eq!(HeadMotion::Static.pose_at(&p, t), p.pose_at(t).sanitized());
        }
    }

    #[test]
    fn yaw_sweep_reaches_30_degrees_a_quarter_period_in_and_keeps_the_position() {
        let p = path();
        let base = p.pose_at(0.0);
        let at_peak = HeadMotion::YawSweep.pose_at(&p, 1.0);
        assert!((angle_between(at_peak.orientation, base.orientation) - 30.0).abs() < 1e-9);
        assert!((at_peak.position - base.position).length() < 1e-12);
        // Yaw about world up keeps the view level.
        let forward = at_peak.orientation * -DVec3::Z;
        assert!(forward.y.abs() < 1e-12);
    }

    #[test]
    fn figure_eight_walks_within_half_a_metre_and_returns_after_a_period() {
        let p = path();
        let base = p.pose_at(0.0).position;
        let max = (0..800)
            .map(|i| (HeadMotion::FigureEight.pose_at(&p, i as f64 * 0.01).position - base).length())
            .fold(0.0, f64::max);
        assert!(max > 0.45 && max <= 0.5 + 1e-9, "{max}");
        assert!((HeadMotion::FigureEight.pose_at(&p, 8.0).position - base).length() < 1e-9);
    }

    #[test]
    fn head_roll_keeps_the_view_direction() {
        let p = path();
        let base = p.pose_at(0.0);
        let rolled = HeadMotion::HeadRoll.pose_at(&p, 0.75);
        assert!((angle_between(rolled.orientation, base.orientation) - 20.0).abs() < 1e-9);
        let (f0, f1) = (base.orientation * -DVec3::Z, rolled.orientation * -DVec3::Z);
        assert!((f0 - f1).length() < 1e-12);
    }
}
