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

impl Track<DVec3> {
    /// Per-axis bounds (lowest, highest) of every value the track takes at any time,
    /// found from the keys, never by sampling: a step or linear track stays within its
    /// keys' values; a cubic spline's segment between keys i and i + 1 is the Bézier
    /// curve of v_i, v_i + b_i·dt/3, v_(i+1) − a_(i+1)·dt/3 and v_(i+1) (its out- and
    /// in-tangents b and a, over dt seconds), which lies in the hull of those four points:
    /// its overshoot between keys included. NaN on both sides when a value is not finite.
    pub fn value_bounds(&self) -> (DVec3, DVec3) {
        let mut points: Vec<DVec3> = Vec::with_capacity(self.values.len());
        match self.interpolation {
            Interpolation::CubicSpline => {
                for i in 0..self.times.len() {
                    let value = self.values[3 * i + 1];
                    points.push(value);
                    if let Some(next_time) = self.times.get(i + 1) {
                        let dt = next_time - self.times[i];
                        points.push(value + self.values[3 * i + 2] * (dt / 3.0));
                        points.push(self.values[3 * (i + 1) + 1] - self.values[3 * (i + 1)] * (dt / 3.0));
                    }
                }
            }
            Interpolation::Step | Interpolation::Linear => points.extend_from_slice(&self.values),
        }
        let bounds = super::Aabb::around(&points);
        (bounds.min, bounds.max)
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

impl Node {
    /// A box holding `within` (a box in this node's frame) carried by the node's local
    /// transform at every time of its animation, from the tracks' value bounds
    /// ([`Track::value_bounds`]), never by sampling: per-axis intervals through the scale
    /// and the translation; a ball of the box's farthest corner where the rotation is
    /// animated (any rotation), the rest rotation and `base` exactly otherwise. NaN where a
    /// value is not finite.
    pub fn reach(&self, within: &super::Aabb) -> super::Aabb {
        use super::Aabb;
        let still = |v: DVec3| (v, v);
        let (scale_lo, scale_hi) = self.tracks.scale.as_ref().map_or(still(self.rest.scale), Track::value_bounds);
        // Each axis: the interval product of the box's side and the scale's range, as the
        // box of the two corners that span it.
        let span = |axis: usize| {
            let (b, s) = ([within.min[axis], within.max[axis]], [scale_lo[axis], scale_hi[axis]]);
            let products = [b[0] * s[0], b[0] * s[1], b[1] * s[0], b[1] * s[1]];
            let lowest = products.iter().copied().fold(f64::INFINITY, f64::min);
            (lowest, products.iter().copied().fold(f64::NEG_INFINITY, f64::max))
        };
        let [x, y, z] = [span(0), span(1), span(2)];
        let scaled = Aabb::around(&[DVec3::new(x.0, y.0, z.0), DVec3::new(x.1, y.1, z.1)]);
        let rotated = match &self.tracks.rotation {
            Some(_) => {
                // f64::max would drop a NaN: kept, so that a bad value is still refused.
                let r = scaled
                    .corners()
                    .iter()
                    .map(|c| c.length())
                    .fold(0.0, |a: f64, b| if b.is_nan() { b } else { a.max(b) });
                Aabb { min: DVec3::splat(-r), max: DVec3::splat(r) }
            }
            None => scaled.transformed(&DMat4::from_quat(self.rest.rotation)),
        };
        let (move_lo, move_hi) =
            self.tracks.translation.as_ref().map_or(still(self.rest.translation), Track::value_bounds);
        Aabb { min: rotated.min + move_lo, max: rotated.max + move_hi }.transformed(&self.base)
    }
}

/// A box holding `within` (a box in node `node`'s frame) in the world at every time of
/// the animation: [`Node::reach`] up the chain of parents.
pub fn reach_in_world(nodes: &[Node], node: usize, within: &super::Aabb) -> super::Aabb {
    let mut bounds = *within;
    let mut at = Some(node);
    while let Some(i) = at.filter(|&i| i < nodes.len()) {
        bounds = nodes[i].reach(&bounds);
        // Parents come first (a smaller index): anything else would loop.
        at = nodes[i].parent.filter(|&p| p < i);
    }
    bounds
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
    fn a_cubic_splines_bounds_hold_its_overshoot_between_keys() {
        // Both keys at 0 with tangents of ±9e5 m/s over 10 s: the curve rises to
        // 9e6 · (s − s²), 2.25e6 m at s = 0.5, between keys that both say 0.
        let bump = track(Interpolation::CubicSpline, &[0.0, 10.0], &[0.0, 0.0, 9e5, -9e5, 0.0, 0.0]);
        assert_eq!((bump.key(0).x, bump.key(1).x), (0.0, 0.0));
        let highest = (0..=1000).map(|k| bump.sample(k as f64 / 100.0).x).fold(0.0, f64::max);
        assert!((highest - 2.25e6).abs() < 1.0, "{highest}");
        let (lo, hi) = bump.value_bounds();
        assert!(lo.x <= 0.0 && hi.x >= highest && hi.x <= 3e6 + 1e-6, "{lo} {hi}");
        // Every sample of random splines lies within their bounds.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..50 {
            let values: Vec<f64> = (0..12).map(|_| 10.0 * next()).collect();
            let spline = track(Interpolation::CubicSpline, &[0.0, 0.5, 2.0, 2.2], &values);
            let (lo, hi) = spline.value_bounds();
            for k in 0..=2200 {
                let v = spline.sample(k as f64 / 1000.0).x;
                assert!(lo.x - 1e-9 <= v && v <= hi.x + 1e-9, "{v} outside {lo} {hi}");
            }
        }
        // Linear and step tracks: their keys.
        let linear = track(Interpolation::Linear, &[0.0, 1.0, 2.0], &[1.0, -3.0, 2.0]);
        assert_eq!(linear.value_bounds(), (DVec3::splat(-3.0), DVec3::splat(2.0)));
        let broken = track(Interpolation::Linear, &[0.0, 1.0], &[1.0, f64::NAN]);
        assert!(broken.value_bounds().0.is_nan());
    }

    #[test]
    fn a_nodes_reach_holds_the_box_at_every_time() {
        let spin = Track {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![DQuat::IDENTITY, DQuat::from_rotation_y(3.0)],
        };
        let grow = track(Interpolation::CubicSpline, &[0.0, 1.0], &[0.0, 1.0, 4.0, -4.0, 2.0, 0.0]);
        let slide = track(Interpolation::CubicSpline, &[0.0, 1.0], &[0.0, -1.0, 6.0, 6.0, 3.0, 0.0]);
        let nodes = vec![
            Node {
                name: "arm".into(),
                parent: None,
                base: DMat4::from_translation(DVec3::new(0.0, 5.0, 0.0)),
                rest: Trs::IDENTITY,
                tracks: NodeTracks { rotation: Some(spin), translation: Some(slide), ..Default::default() },
            },
            Node {
                name: "hand".into(),
                parent: Some(0),
                base: DMat4::IDENTITY,
                rest: Trs { translation: DVec3::new(2.0, 0.0, 0.0), ..Trs::IDENTITY },
                tracks: NodeTracks { scale: Some(grow), ..Default::default() },
            },
        ];
        let local = super::super::Aabb { min: DVec3::new(-0.5, 0.0, -0.1), max: DVec3::new(0.5, 1.0, 0.1) };
        let reach = reach_in_world(&nodes, 1, &local);
        for k in 0..=500 {
            let world = world_transforms(&nodes, k as f64 / 500.0)[1];
            for c in local.corners() {
                let p = world.transform_point3(c);
                assert!(p.cmpge(reach.min - 1e-9).all() && p.cmple(reach.max + 1e-9).all(), "{p} outside {reach:?}");
            }
        }
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
