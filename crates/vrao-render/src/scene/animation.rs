//! Moving objects: a hierarchy of nodes whose local transforms follow keyframe tracks
//! (glTF animation channels, or a TOML scene's `[mesh.animation]`).
//!
//! Only meshes that hang below an animated node keep a node ([`super::Mesh::node`]);
//! everything static is baked into world space at load, so a still scene carries no nodes
//! at all and the renderer adds nothing for motion. A moving mesh's positions are in its
//! node's local frame, and the renderer moves it by the node's world transform on the GPU
//! (no vertex re-upload).
//!
//! Time: every track is sampled at `t` modulo the scene's loop period
//! ([`super::Scene::animation_period`], the end of the longest track), so an animation
//! plays in a loop in `vrao run` and `vrao render --time T` names any time.

use glam::{DMat4, DQuat, DVec3};

/// How values between two keys are found (glTF `sampler.interpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The earlier key's value until the next key.
    Step,
    /// Linear for translation and scale, shortest-path slerp for rotation.
    Linear,
    /// Cubic Hermite spline; each key stores (in-tangent, value, out-tangent).
    CubicSpline,
}

/// Keyframes of one property. For [`Interpolation::CubicSpline`] `values` holds three
/// entries per key (in-tangent, value, out-tangent), otherwise one.
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T> {
    /// How to interpolate between keys.
    pub interpolation: Interpolation,
    /// Key times in seconds, finite, non-negative and strictly increasing; at least one.
    pub times: Vec<f64>,
    /// One value per key (three for cubic splines).
    pub values: Vec<T>,
}

/// What a track interpolates: vectors and rotations.
pub trait Keyframed: Copy {
    /// Linear (or, for rotations, spherical) interpolation.
    fn lerp_to(self, other: Self, s: f64) -> Self;
    /// a·x + b·y (for the Hermite basis).
    fn combine(a: f64, x: Self, b: f64, y: Self) -> Self;
    /// A value that is ready to use (rotations normalised).
    fn finish(self) -> Self {
        self
    }
}

impl Keyframed for DVec3 {
    fn lerp_to(self, other: Self, s: f64) -> Self {
        self.lerp(other, s)
    }
    fn combine(a: f64, x: Self, b: f64, y: Self) -> Self {
        a * x + b * y
    }
}

impl Keyframed for DQuat {
    fn lerp_to(self, other: Self, s: f64) -> Self {
        self.slerp(other, s)
    }
    fn combine(a: f64, x: Self, b: f64, y: Self) -> Self {
        DQuat::from_vec4(a * glam::DVec4::from(x) + b * glam::DVec4::from(y))
    }
    fn finish(self) -> Self {
        let n = self.length();
        if n > 1e-12 && n.is_finite() {
            self / n
        } else {
            DQuat::IDENTITY
        }
    }
}

impl<T: Keyframed> Track<T> {
    /// The last key's time.
    pub fn end(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Values per key: 3 for cubic splines (in-tangent, value, out-tangent), else 1.
    pub fn stride(&self) -> usize {
        if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        }
    }

    /// Whether times and values agree in count and the times are strictly increasing,
    /// finite and non-negative (loaders check this and name what is wrong).
    pub fn is_well_formed(&self) -> bool {
        !self.times.is_empty()
            && self.values.len() == self.times.len() * self.stride()
            && self.times.iter().all(|t| t.is_finite() && *t >= 0.0)
            && self.times.windows(2).all(|w| w[1] > w[0])
    }

    fn key(&self, i: usize) -> T {
        self.values[i * self.stride() + self.stride() / 2]
    }

    /// The value at `t` seconds, clamped to the first and last key.
    pub fn sample(&self, t: f64) -> T {
        let times = &self.times;
        if t <= times[0] || times.len() == 1 {
            return self.key(0).finish();
        }
        let last = times.len() - 1;
        if t >= times[last] {
            return self.key(last).finish();
        }
        // The key interval holding t: times[i] <= t < times[i + 1].
        let i = times.partition_point(|&k| k <= t) - 1;
        let (t0, t1) = (times[i], times[i + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => self.key(i).finish(),
            Interpolation::Linear => self.key(i).lerp_to(self.key(i + 1), s).finish(),
            Interpolation::CubicSpline => {
                // glTF's Hermite form: p(s) = h00·v0 + h10·dt·b0 + h01·v1 + h11·dt·a1, where
                // b0 is key i's out-tangent and a1 key i+1's in-tangent.
                let v0 = self.values[3 * i + 1];
                let b0 = self.values[3 * i + 2];
                let a1 = self.values[3 * (i + 1)];
                let v1 = self.values[3 * (i + 1) + 1];
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                let first = T::combine(h00, v0, h10 * dt, b0);
                let second = T::combine(h01, v1, h11 * dt, a1);
                T::combine(1.0, first, 1.0, second).finish()
            }
        }
    }
}

/// A local transform: translation, rotation and scale (applied scale first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation in metres.
    pub translation: DVec3,
    /// Unit rotation.
    pub rotation: DQuat,
    /// Per-axis scale.
    pub scale: DVec3,
}

impl Trs {
    /// No transform.
    pub const IDENTITY: Trs = Trs { translation: DVec3::ZERO, rotation: DQuat::IDENTITY, scale: DVec3::ONE };

    /// The matrix T·R·S.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// The animated properties of one node; a property without a track keeps its rest value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeTracks {
    /// Translation keys.
    pub translation: Option<Track<DVec3>>,
    /// Rotation keys (unit quaternions).
    pub rotation: Option<Track<DQuat>>,
    /// Scale keys.
    pub scale: Option<Track<DVec3>>,
}

impl NodeTracks {
    /// Whether any property is animated.
    pub fn is_empty(&self) -> bool {
        self.translation.is_none() && self.rotation.is_none() && self.scale.is_none()
    }
    /// The last key time over the tracks.
    pub fn end(&self) -> f64 {
        let t = self.translation.as_ref().map_or(0.0, Track::end);
        let r = self.rotation.as_ref().map_or(0.0, Track::end);
        let s = self.scale.as_ref().map_or(0.0, Track::end);
        t.max(r).max(s)
    }
}

/// One node of the motion hierarchy: a rest transform relative to its parent (or to the
/// world), and the tracks that animate it.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Name from the source file.
    pub name: String,
    /// Index of the parent in [`super::Scene::nodes`] (always smaller than this node's), or
    /// `None` for a node placed in the world.
    pub parent: Option<usize>,
    /// A fixed transform outside the animated one: the node's local transform is
    /// `base · TRS(t)`. For a root node it is the world transform of its static ancestors
    /// (identity when it sits in the world); for a static node given as a matrix (glTF
    /// `matrix`, which cannot be animated) it is that matrix with `rest` the identity.
    pub base: DMat4,
    /// The TRS when no track overrides it.
    pub rest: Trs,
    /// The animated properties.
    pub tracks: NodeTracks,
}

impl Node {
    /// The local transform (`base · TRS`) at `t` seconds (already wrapped into the loop period).
    pub fn local_at(&self, t: f64) -> DMat4 {
        let mut trs = self.rest;
        if let Some(track) = &self.tracks.translation {
            trs.translation = track.sample(t);
        }
        if let Some(track) = &self.tracks.rotation {
            trs.rotation = track.sample(t);
        }
        if let Some(track) = &self.tracks.scale {
            trs.scale = track.sample(t);
        }
        self.base * trs.matrix()
    }
}

/// World-from-local transforms of every node at `t` (already wrapped), parents first.
pub fn world_transforms(nodes: &[Node], t: f64) -> Vec<DMat4> {
    let mut world: Vec<DMat4> = Vec::with_capacity(nodes.len());
    for node in nodes {
        let local = node.local_at(t);
        let m = match node.parent {
            Some(p) if p < world.len() => world[p] * local,
            _ => local,
        };
        world.push(m);
    }
    world
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(interpolation: Interpolation, times: &[f64], values: &[f64]) -> Track<DVec3> {
        Track { interpolation, times: times.to_vec(), values: values.iter().map(|&v| DVec3::splat(v)).collect() }
    }

    #[test]
    fn step_linear_and_cubic_tracks_match_their_definitions() {
        let step = track(Interpolation::Step, &[0.0, 1.0, 2.0], &[0.0, 10.0, 20.0]);
        assert_eq!(step.sample(0.99).x, 0.0);
        assert_eq!(step.sample(1.0).x, 10.0);
        assert_eq!(step.sample(5.0).x, 20.0);
        let linear = track(Interpolation::Linear, &[1.0, 3.0], &[2.0, 6.0]);
        assert_eq!(linear.sample(0.0).x, 2.0);
        assert_eq!(linear.sample(2.0).x, 4.0);
        assert_eq!(linear.sample(2.5).x, 5.0);
        // Cubic with zero tangents is smoothstep between the values; with tangents equal to
        // the slope of a line it reproduces the line.
        let flat = track(Interpolation::CubicSpline, &[0.0, 1.0], &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        assert!((flat.sample(0.5).x - 0.5).abs() < 1e-12);
        assert!((flat.sample(0.25).x - (3.0 * 0.0625 - 2.0 * 0.015625)).abs() < 1e-12);
        let line = track(Interpolation::CubicSpline, &[0.0, 2.0], &[3.0, 1.0, 3.0, 3.0, 7.0, 3.0]);
        for t in [0.3, 0.9, 1.7] {
            assert!((line.sample(t).x - (1.0 + 3.0 * t)).abs() < 1e-12);
        }
        assert!(line.is_well_formed() && !track(Interpolation::Linear, &[1.0, 1.0], &[0.0, 1.0]).is_well_formed());
    }

    #[test]
    fn rotations_slerp_and_stay_unit() {
        let quarter = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
        let t = Track {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![DQuat::IDENTITY, quarter],
        };
        let half = t.sample(0.5);
        assert!((half.length() - 1.0).abs() < 1e-12);
        assert!(half.angle_between(DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4)) < 1e-9);
    }

    #[test]
    fn children_follow_their_parents() {
        let spin = Track {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![DQuat::IDENTITY, DQuat::from_rotation_y(std::f64::consts::PI)],
        };
        let nodes = vec![
            Node {
                name: "hinge".into(),
                parent: None,
                base: DMat4::IDENTITY,
                rest: Trs { translation: DVec3::new(1.0, 0.0, 0.0), ..Trs::IDENTITY },
                tracks: NodeTracks { rotation: Some(spin), ..Default::default() },
            },
            Node {
                name: "door".into(),
                parent: Some(0),
                base: DMat4::IDENTITY,
                rest: Trs { translation: DVec3::new(0.5, 0.0, 0.0), ..Trs::IDENTITY },
                tracks: NodeTracks::default(),
            },
        ];
        let world = world_transforms(&nodes, 1.0);
        let p = world[1].transform_point3(DVec3::ZERO);
        assert!((p - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-9, "{p}");
    }
}
