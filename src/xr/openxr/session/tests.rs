//! Tests of `session.rs`.

use super::tracking::{default_view, orientation_only};
use super::*;

#[test]
fn xr_fov_keeps_its_signs() {
    let fov = fov_from_xr(&xr::Fovf { angle_left: -0.8, angle_right: 0.7, angle_up: 0.9, angle_down: -0.85 });
    assert_eq!((fov.left, fov.right, fov.up, fov.down), (-0.8, 0.7, 0.9, -0.85));
    assert!(fov.validate().is_ok());
}

#[test]
fn xr_pose_becomes_a_normalised_head_pose() {
    let pose = xr::Posef {
        orientation: xr::Quaternionf { x: 0.0, y: 2.0, z: 0.0, w: 0.0 },
        position: xr::Vector3f { x: 1.0, y: 1.5, z: -2.0 },
    };
    let p = pose_from_xr(&pose);
    assert_eq!(p.position, DVec3::new(1.0, 1.5, -2.0));
    // 180° about +Y: looking down +Z.
    assert!((p.orientation * -DVec3::Z - DVec3::Z).length() < 1e-12);
}

fn view(yaw: f32, position: [f32; 3]) -> xr::View {
    let q = Quat::from_rotation_y(yaw);
    xr::View {
        pose: xr::Posef {
            orientation: xr::Quaternionf { x: q.x, y: q.y, z: q.z, w: q.w },
            position: xr::Vector3f { x: position[0], y: position[1], z: position[2] },
        },
        fov: default_view(1.0).fov,
    }
}

fn position(v: &xr::View) -> Vec3 {
    Vec3::new(v.pose.position.x, v.pose.position.y, v.pose.position.z)
}

#[test]
fn orientation_only_holds_the_head_and_turns_the_eyes_about_it() {
    let anchor = [view(0.0, [0.968, 1.6, 2.0]), view(0.0, [1.032, 1.6, 2.0])];
    // Turned 90° left; the runtime's positions are undefined without POSITION_VALID.
    let turn = std::f32::consts::FRAC_PI_2;
    let located = [view(turn, [f32::NAN; 3]), view(turn, [99.0, 99.0, 99.0])];
    let merged = orientation_only(&located, &anchor);
    // Facing -X now: the left eye is on +Z of the head's centre, the right on -Z.
    assert!((position(&merged[0]) - Vec3::new(1.0, 1.6, 2.032)).length() < 1e-5, "{:?}", position(&merged[0]));
    assert!((position(&merged[1]) - Vec3::new(1.0, 1.6, 1.968)).length() < 1e-5, "{:?}", position(&merged[1]));
    for (m, l) in merged.iter().zip(&located) {
        assert_eq!(m.pose.orientation, l.pose.orientation, "the located orientation is used");
        assert_eq!(m.fov, l.fov);
    }
    // Not turned: exactly the anchor's eyes.
    let merged = orientation_only(&[view(0.0, [5.0; 3]), view(0.0, [5.0; 3])], &anchor);
    assert!((position(&merged[0]) - position(&anchor[0])).length() < 1e-6);
    assert!((position(&merged[1]) - position(&anchor[1])).length() < 1e-6);
}

#[test]
fn tracking_keeps_the_last_valid_position_and_warns_once_per_loss() {
    use xr::ViewStateFlags as F;
    let full = F::ORIENTATION_VALID | F::POSITION_VALID | F::ORIENTATION_TRACKED | F::POSITION_TRACKED;
    let orientation = F::ORIENTATION_VALID | F::ORIENTATION_TRACKED;
    let mut tracking = Tracking::default();
    let valid = [view(0.0, [-0.03, 1.7, 0.0]), view(0.0, [0.03, 1.7, 0.0])];
    let (views, warning) = tracking.merge(full, &valid);
    assert_eq!(warning, None);
    assert_eq!(position(&views[0]), position(&valid[0]));

    // Position lost: warned at the first frame of the episode only.
    let drifted = [view(0.3, [4.0, 0.0, 0.0]), view(0.3, [4.0, 0.0, 0.0])];
    let (views, warning) = tracking.merge(orientation, &drifted);
    assert!(warning.is_some_and(|w| w.contains("orientation only")), "{warning:?}");
    let center = (position(&views[0]) + position(&views[1])) * 0.5;
    assert!((center - Vec3::new(0.0, 1.7, 0.0)).length() < 1e-6, "the head stays put: {center:?}");
    assert_eq!(views[0].pose.orientation, drifted[0].pose.orientation);
    for _ in 0..3 {
        assert_eq!(tracking.merge(orientation, &drifted).1, None, "no warning every frame");
    }
    // Orientation lost too, within the same episode: the last views, no new warning.
    let (held, warning) = tracking.merge(F::EMPTY, &[]);
    assert_eq!(warning, None);
    assert_eq!(held[0].pose.orientation, drifted[0].pose.orientation);
    assert!((position(&held[0]) - position(&views[0])).length() < 1e-6);

    // Back, then lost again: a new episode, a new warning.
    let moved = [view(0.0, [1.0, 1.7, 0.0]), view(0.0, [1.06, 1.7, 0.0])];
    assert_eq!(tracking.merge(full, &moved).1, None);
    let (views, warning) = tracking.merge(orientation, &drifted);
    assert!(warning.is_some());
    let center = (position(&views[0]) + position(&views[1])) * 0.5;
    assert!((center - Vec3::new(1.03, 1.7, 0.0)).length() < 1e-6, "held at the newest valid position");
}

#[test]
fn tracking_before_any_valid_pose_uses_the_default_views() {
    let mut tracking = Tracking::default();
    let (views, warning) = tracking.merge(xr::ViewStateFlags::EMPTY, &[]);
    assert!(warning.is_some_and(|w| w.contains("tracking lost")));
    assert_eq!(position(&views[0]), position(&default_view(-1.0)));
    // Orientation only from the start: the default eyes, turned.
    let (views, _) = tracking.merge(xr::ViewStateFlags::ORIENTATION_VALID, &[view(0.0, [9.0; 3]), view(0.0, [9.0; 3])]);
    assert!((position(&views[1]) - Vec3::new(0.032, 0.0, 0.0)).length() < 1e-6);
}

#[test]
fn failed_calls_name_the_call_and_the_xr_result() {
    let text = crate::xr::openxr::xr_call_failed("xrReleaseSwapchainImage", xr::sys::Result::ERROR_INSTANCE_LOST);
    assert!(text.starts_with("xrReleaseSwapchainImage: XR_ERROR_INSTANCE_LOST ("), "{text}");
    let fill = FillError::Xr("xrWaitSwapchainImage", xr::sys::Result::ERROR_SESSION_LOST);
    assert!(fill.to_string().starts_with("xrWaitSwapchainImage: XR_ERROR_SESSION_LOST"), "{fill}");
}
