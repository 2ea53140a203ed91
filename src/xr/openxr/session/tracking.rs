//! The views a frame is rendered with: OpenXR's located views merged with the last valid
//! ones when tracking is partial or lost (orientation-only tracking), and their
//! conversion to vrao's poses and fields of view.

use super::*;

/// The views frames are rendered with, when tracking is partial or lost too.
#[derive(Default)]
pub(super) struct Tracking {
    /// The last views with a valid orientation: used whole when orientation is lost.
    last: Option<[xr::View; 2]>,
    /// The last views with a valid position as well: where the head is held while only
    /// orientation is tracked.
    anchor: Option<[xr::View; 2]>,
    /// Within a position-loss episode (warned about at its start only).
    position_lost: bool,
}

impl Tracking {
    /// The views to render with, from what xrLocateViews answered; and a warning when a
    /// position-loss episode begins (not every frame of it).
    pub(super) fn merge(
        &mut self,
        flags: xr::ViewStateFlags,
        located: &[xr::View],
    ) -> ([xr::View; 2], Option<&'static str>) {
        let orientation = flags.contains(xr::ViewStateFlags::ORIENTATION_VALID) && located.len() == 2;
        // Without POSITION_VALID the located positions are undefined.
        let position = orientation && flags.contains(xr::ViewStateFlags::POSITION_VALID);
        let views = if position {
            self.anchor = Some([located[0], located[1]]);
            [located[0], located[1]]
        } else if orientation {
            orientation_only(&[located[0], located[1]], &self.anchor.unwrap_or(default_views()))
        } else {
            self.last.unwrap_or(default_views())
        };
        if orientation {
            self.last = Some(views);
        }
        let warning = (!position && !self.position_lost).then_some(if orientation {
            "position tracking lost: orientation only, the head held at its last position"
        } else {
            "tracking lost: the last pose is held"
        });
        self.position_lost = !position;
        (views, warning)
    }
}

/// Orientation-only tracking: each located view's orientation and field of view, with
/// the head held where `anchor` (the last views with a valid position) had it. The eyes
/// keep their offsets from the head's centre, turned with the head, so the stereo
/// baseline follows the head.
pub(super) fn orientation_only(located: &[xr::View; 2], anchor: &[xr::View; 2]) -> [xr::View; 2] {
    let vec = |v: xr::Vector3f| Vec3::new(v.x, v.y, v.z);
    let quat = |q: xr::Quaternionf| Quat::from_xyzw(q.x, q.y, q.z, q.w).normalize();
    let center = (vec(anchor[0].pose.position) + vec(anchor[1].pose.position)) * 0.5;
    std::array::from_fn(|i| {
        let offset = quat(anchor[i].pose.orientation).inverse() * (vec(anchor[i].pose.position) - center);
        let p = center + quat(located[i].pose.orientation) * offset;
        xr::View {
            pose: xr::Posef {
                orientation: located[i].pose.orientation,
                position: xr::Vector3f { x: p.x, y: p.y, z: p.z },
            },
            fov: located[i].fov,
        }
    })
}

pub(super) fn pose_from_xr(pose: &xr::Posef) -> HeadPose {
    let o = pose.orientation;
    let p = pose.position;
    HeadPose {
        position: DVec3::new(p.x as f64, p.y as f64, p.z as f64),
        orientation: DQuat::from_xyzw(o.x as f64, o.y as f64, o.z as f64, o.w as f64),
    }
    .sanitized()
}

/// OpenXR's XrFovf and vrao's `Fov` are the same four angles with the same signs (left
/// and down negative).
pub(super) fn fov_from_xr(fov: &xr::Fovf) -> Fov {
    Fov { left: fov.angle_left, right: fov.angle_right, up: fov.angle_up, down: fov.angle_down }
}

/// Both views before tracking.
pub(super) fn default_views() -> [xr::View; 2] {
    [default_view(-1.0), default_view(1.0)]
}

/// A view before tracking: 32 mm to the side, 45° each way.
pub(super) fn default_view(side: f32) -> xr::View {
    let a = std::f32::consts::FRAC_PI_4;
    xr::View {
        pose: xr::Posef {
            orientation: xr::Quaternionf::IDENTITY,
            position: xr::Vector3f { x: side * 0.032, y: 0.0, z: 0.0 },
        },
        fov: xr::Fovf { angle_left: -a, angle_right: a, angle_up: a, angle_down: -a },
    }
}
