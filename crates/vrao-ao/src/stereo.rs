//! Eyes: head pose, IPD, per-eye asymmetric field of view (OpenXR's form) and the
//! reversed-Z infinite-far projection. `view_position_from_depth` is the one place that
//! turns a depth sample back into a view-space position; `shaders/common.wgsl` mirrors it.

use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3, Mat4};

/// Default near plane in metres (the far plane is at infinity).
pub const DEFAULT_NEAR: f64 = 0.05;
/// Head (or eye) pose in world space: where it is and which way it faces.
/// The pose looks down its local −Z with +Y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadPose {
    /// World-space position in metres.
    pub position: DVec3,
    /// World-from-local rotation (unit quaternion).
    pub orientation: DQuat,
}

impl HeadPose {
    /// At the origin, looking down world −Z with +Y up.
    pub const IDENTITY: HeadPose = HeadPose { position: DVec3::ZERO, orientation: DQuat::IDENTITY };

    /// A pose at `eye` looking towards `target`, with world +Y as up (or +Z when looking
    /// straight up or down). Returns `None` when `eye` and `target` coincide.
    pub fn look_at(eye: DVec3, target: DVec3) -> Option<HeadPose> {
        let forward = (target - eye).try_normalize()?;
        let up = if forward.cross(DVec3::Y).length_squared() < 1e-12 { DVec3::Z } else { DVec3::Y };
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let rotation = glam::DMat3::from_cols(right, true_up, -forward);
        Some(HeadPose { position: eye, orientation: DQuat::from_mat3(&rotation).normalize() })
    }

    /// Orientation normalised; a zero or non-finite quaternion becomes identity.
    pub fn sanitized(&self) -> HeadPose {
        let q = self.orientation;
        let len = q.length();
        let orientation = if len.is_finite() && len > 1e-12 { q / len } else { DQuat::IDENTITY };
        HeadPose { position: self.position, orientation }
    }

    /// World-from-local transform.
    pub fn world_from_local(&self) -> DMat4 {
        DMat4::from_rotation_translation(self.orientation, self.position)
    }
}

/// Field of view as four angles in radians, as OpenXR's `XrFovf`: `left` and `down` are
/// negative for a view that contains its own axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fov {
    /// Angle of the left edge (negative left of the view axis).
    pub left: f32,
    /// Angle of the right edge.
    pub right: f32,
    /// Angle of the top edge.
    pub up: f32,
    /// Angle of the bottom edge (negative below the view axis).
    pub down: f32,
}

impl Fov {
    /// Tangents of the four angles (left, right, up, down).
    pub fn tangents(&self) -> [f64; 4] {
        [(self.left as f64).tan(), (self.right as f64).tan(), (self.up as f64).tan(), (self.down as f64).tan()]
    }

    /// The same field of view mirrored left/right (the other eye of a symmetric headset).
    pub fn mirrored(&self) -> Fov {
        Fov { left: -self.right, right: -self.left, up: self.up, down: self.down }
    }

    /// Checks that every angle is finite and within ±90° and that the view is not empty.
    pub fn validate(&self) -> Result<(), InvalidFov> {
        let half = std::f32::consts::FRAC_PI_2;
        for (name, a) in [("left", self.left), ("right", self.right), ("up", self.up), ("down", self.down)] {
            if !a.is_finite() || a.abs() >= half - 1e-4 {
                return Err(InvalidFov(format!("fov angle {name} = {a} rad is not in (-90°, 90°)")));
            }
        }
        if self.right <= self.left || self.up <= self.down {
            return Err(InvalidFov(format!("fov {self:?} is empty (right must exceed left, up must exceed down)")));
        }
        Ok(())
    }
}

/// A field of view that cannot be rendered ([`Fov::validate`]), in one line for the user.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidFov(pub String);

impl From<InvalidFov> for Error {
    /// A field of view is input (a profile, a scene, a runtime's views): `Error::Input`.
    fn from(error: InvalidFov) -> Error {
        Error::input(error.0)
    }
}

impl From<InvalidFov> for String {
    fn from(error: InvalidFov) -> String {
        error.0
    }
}

impl Fov {
    /// Reversed-Z projection with an infinite far plane for an asymmetric frustum.
    /// Clip z = near and w = −z_view, so depth = near / distance: 1 at the near plane,
    /// 0 at infinity. Built in f64 and rounded once.
    pub fn reversed_z_projection(&self, near: f64) -> DMat4 {
        let [l, r, u, d] = self.tangents();
        DMat4::from_cols_array(&[
            2.0 / (r - l),
            0.0,
            0.0,
            0.0,
            0.0,
            2.0 / (u - d),
            0.0,
            0.0,
            (r + l) / (r - l),
            (u + d) / (u - d),
            0.0,
            -1.0,
            0.0,
            0.0,
            near,
            0.0,
        ])
    }

    /// View-space position of the surface seen at texture coordinate `uv` (0..1, origin at
    /// the top-left) with reversed-Z depth `depth`. Uses the frustum tangents directly, so
    /// no matrix inverse loses precision. `depth` must be > 0 (0 is the sky at infinity).
    pub fn view_position_from_depth(uv: [f64; 2], depth: f64, fov: &Fov, near: f64) -> DVec3 {
        let [l, r, u, d] = fov.tangents();
        let distance = near / depth; // −z_view
        let tan_x = l + (r - l) * uv[0];
        let tan_y = u + (d - u) * uv[1];
        DVec3::new(tan_x * distance, tan_y * distance, -distance)
    }
}

/// Which eye; the index is also the texture-array layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EyeSide {
    /// The left eye, layer 0.
    Left = 0,
    /// The right eye, layer 1.
    Right = 1,
}

/// One eye: its pose in world space and its field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eye {
    /// Which eye (and texture-array layer) this is.
    pub side: EyeSide,
    /// The eye's own pose in world space.
    pub pose: HeadPose,
    /// The eye's asymmetric field of view.
    pub fov: Fov,
}

impl Eye {
    /// View-from-world transform (f64).
    pub fn view_from_world(&self) -> DMat4 {
        self.pose.world_from_local().inverse()
    }

    /// Clip-from-world for geometry stored relative to `anchor`, computed in f64 so a
    /// scene far from the origin keeps its precision near the eye.
    pub fn clip_from_anchored(&self, anchor: DVec3, near: f64) -> Mat4 {
        let view = self.view_from_world() * DMat4::from_translation(anchor);
        (Fov::reversed_z_projection(&self.fov, near) * view).as_mat4()
    }

    /// Rotation part of view-from-world, for normals.
    pub fn view_rotation(&self) -> glam::Mat3 {
        glam::DMat3::from_quat(self.pose.orientation.inverse()).as_mat3()
    }

    /// Where a world point lands in this eye: (u, v) in 0..1 from the top-left and the
    /// reversed-Z depth; `None` behind the eye.
    pub fn project(&self, world: DVec3, near: f64) -> Option<([f64; 2], f64)> {
        let v = self.view_from_world().transform_point3(world);
        if v.z >= 0.0 {
            return None;
        }
        let clip = Fov::reversed_z_projection(&self.fov, near) * v.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        Some(([(ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5], ndc.z))
    }
}

/// Both eyes of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePair {
    /// Left, then right.
    pub eyes: [Eye; 2],
    /// Near plane in metres (the far plane is at infinity).
    pub near: f64,
}

impl EyePair {
    /// Eyes at ∓ipd/2 along the head's local +X, looking the head's way (parallel axes,
    /// as OpenXR runtimes report them).
    pub fn from_head(head: &HeadPose, ipd: f64, fov_left: Fov, fov_right: Fov, near: f64) -> EyePair {
        let head = head.sanitized();
        let right_axis = head.orientation * DVec3::X;
        let eye = |side, sign: f64, fov| Eye {
            side,
            pose: HeadPose { position: head.position + right_axis * (sign * ipd * 0.5), orientation: head.orientation },
            fov,
        };
        EyePair { eyes: [eye(EyeSide::Left, -1.0, fov_left), eye(EyeSide::Right, 1.0, fov_right)], near }
    }

    /// A single (mono) view from the head itself, as the single-pass display mode uses.
    pub fn mono(head: &HeadPose, fov: Fov) -> Eye {
        Eye { side: EyeSide::Left, pose: head.sanitized(), fov }
    }
}

impl Eye {
    /// The world-space direction (unit) through the centre of `pixel` of an eye whose image
    /// is `size` pixels (x right, y down from the top-left corner).
    pub fn pixel_ray(&self, size: (u32, u32), pixel: (f64, f64)) -> DVec3 {
        let [l, r, u, d] = self.fov.tangents();
        let (s, t) = (pixel.0 / size.0 as f64, pixel.1 / size.1 as f64);
        (self.pose.orientation * DVec3::new(l + (r - l) * s, u + (d - u) * t, -1.0)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Vive-class left-eye frustum (52° up and down, 45° nasal, 55.6° out).
    fn vive_fov() -> Fov {
        let (vertical, inward) = (52f64.to_radians().tan(), 45f64.to_radians().tan());
        let outward = 2.0 * vertical * 1080.0 / 1200.0 - inward;
        Fov {
            left: -(outward.atan() as f32),
            right: inward.atan() as f32,
            up: vertical.atan() as f32,
            down: -(vertical.atan() as f32),
        }
    }

    #[test]
    fn projection_maps_near_plane_to_one_and_infinity_to_zero() {
        let fov = vive_fov();
        let p = Fov::reversed_z_projection(&fov, 0.1);
        let near = p * glam::DVec4::new(0.0, 0.0, -0.1, 1.0);
        assert!((near.z / near.w - 1.0).abs() < 1e-12);
        let far = p * glam::DVec4::new(0.0, 0.0, -1e12, 1.0);
        assert!((far.z / far.w).abs() < 1e-12);
    }

    #[test]
    fn frustum_edges_map_to_ndc_edges() {
        let fov = vive_fov();
        let [l, r, u, d] = fov.tangents();
        let p = Fov::reversed_z_projection(&fov, 0.05);
        for (x, y, ex, ey) in [(l, u, -1.0, 1.0), (r, d, 1.0, -1.0)] {
            let c = p * glam::DVec4::new(x * 3.0, y * 3.0, -3.0, 1.0);
            assert!((c.x / c.w - ex).abs() < 1e-12 && (c.y / c.w - ey).abs() < 1e-12);
        }
    }

    #[test]
    fn depth_round_trip_is_exact_in_f32_from_5cm_to_10km() {
        let fov = vive_fov().mirrored();
        let near = DEFAULT_NEAR;
        let eye = Eye { side: EyeSide::Right, pose: HeadPose::IDENTITY, fov };
        for distance in [0.05, 0.3, 1.0, 17.0, 250.0, 1e3, 1e4] {
            let world = DVec3::new(0.2 * distance, -0.1 * distance, -distance);
            let (uv, depth) = eye.project(world, near).unwrap();
            let depth32 = depth as f32 as f64; // what a Depth32Float target stores
            let back = Fov::view_position_from_depth(uv, depth32, &fov, near);
            let rel = (back - world).length() / world.length();
            assert!(rel < 1e-6, "distance {distance}: relative error {rel}");
        }
    }

    #[test]
    fn unnormalised_quaternion_is_normalised() {
        let pose = HeadPose { position: DVec3::ZERO, orientation: DQuat::from_xyzw(0.0, 0.0, 0.0, 7.0) };
        assert!((pose.sanitized().orientation.length() - 1.0).abs() < 1e-12);
        let zero = HeadPose { position: DVec3::ZERO, orientation: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0) };
        assert_eq!(zero.sanitized().orientation, DQuat::IDENTITY);
    }
}
