//! When a second depth layer cannot hold anything: a scene whose every triangle lies on
//! the boundary of one convex region (an open plane, a crease, an empty box room), seen
//! from inside that region.
//!
//! Why that is enough: the geometry lies in the closed convex region C and on its
//! boundary. A view ray from an eye inside C runs through C's interior until it leaves C,
//! once, and never comes back (C is convex): it meets the geometry at most at that exit.
//! So behind the first surface of every pixel there is none, and the depth peel would
//! only clear its target. A scene of coplanar triangles alone (an open plane) meets any
//! ray that does not lie in its plane at most once, from either side.
//!
//! The test is exact on the triangles as given, within a tolerance of 1e-6 of the scene's
//! extent, and deliberately narrow: moving objects (which could leave the shell) and
//! scenes of more than [`MAX_TRIANGLES`] triangles (whose test would cost more than it
//! could save, and which are never one convex shell in practice) are not tested.

use super::Scene;
use glam::DVec3;

/// Scenes with more triangles than this are not tested (module docs).
pub const MAX_TRIANGLES: usize = 4096;

/// The half-spaces whose intersection's boundary holds every triangle of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexShell {
    /// (unit normal pointing inside, offset): a point p is inside when normal·p > offset.
    planes: Vec<(DVec3, f64)>,
    /// How far inside a point must be to count (1e-6 of the scene's extent).
    tolerance: f64,
}

impl ConvexShell {
    /// The shell of `scene` when it is one (module docs), else `None`.
    pub fn of(scene: &Scene) -> Option<ConvexShell> {
        if scene.meshes.iter().any(|m| m.node.is_some()) {
            return None;
        }
        let triangles: usize = scene.meshes.iter().map(|m| m.indices.len() / 3).sum();
        if triangles == 0 || triangles > MAX_TRIANGLES {
            return None;
        }
        let vertices: Vec<DVec3> =
            scene.meshes.iter().flat_map(|m| m.positions.iter().map(move |p| m.origin + p.as_dvec3())).collect();
        let bounds = scene.bounds();
        let extent = (bounds.max - bounds.min).length();
        if !extent.is_finite() {
            return None;
        }
        let tolerance = 1e-6 * extent.max(1e-9);
        let mut planes: Vec<(DVec3, f64)> = Vec::new();
        for mesh in &scene.meshes {
            for t in mesh.indices.chunks_exact(3) {
                let [a, b, c] = [0, 1, 2].map(|k| mesh.origin + mesh.positions[t[k] as usize].as_dvec3());
                let Some(n) = (b - a).cross(c - a).try_normalize() else {
                    continue; // a degenerate triangle covers no pixel
                };
                let (mut below, mut above) = (false, false);
                for v in &vertices {
                    let s = n.dot(*v - a);
                    below |= s < -tolerance;
                    above |= s > tolerance;
                    if below && above {
                        return None;
                    }
                }
                // All coplanar: a plane every ray not in it meets once, from either side.
                if !below && !above {
                    continue;
                }
                let inside = if above { n } else { -n };
                let offset = inside.dot(a);
                if !planes.iter().any(|(m, d)| m.dot(inside) > 1.0 - 1e-9 && (d - offset).abs() <= tolerance) {
                    planes.push((inside, offset));
                }
            }
        }
        Some(ConvexShell { planes, tolerance })
    }

    /// Whether `point` lies inside every plane of the shell (strictly, by the tolerance).
    pub fn contains(&self, point: DVec3) -> bool {
        self.planes.iter().all(|(n, d)| n.dot(point) - d > self.tolerance)
    }

    /// The shell's planes (none for a scene of one plane).
    pub fn planes(&self) -> usize {
        self.planes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn builtin(name: &str) -> Scene {
        crate::scene::builtin::load(name).unwrap()
    }

    #[test]
    fn an_open_plane_and_a_crease_are_shells_a_furnished_room_is_not() {
        let plane = ConvexShell::of(&builtin("plane")).expect("one plane");
        assert_eq!(plane.planes(), 0);
        assert!(plane.contains(DVec3::new(0.0, -5.0, 0.0)), "either side of a lone plane");
        let crease = ConvexShell::of(&builtin("crease")).expect("two half-planes bound a convex wedge");
        assert_eq!(crease.planes(), 2);
        let eye = builtin("crease").head.pose_at(0.0).position;
        assert!(crease.contains(eye));
        assert!(ConvexShell::of(&builtin("furnished")).is_none());
        assert!(ConvexShell::of(&builtin("room")).is_none(), "a cube inside a room");
    }

    #[test]
    fn an_eye_outside_the_shell_may_see_two_surfaces() {
        // The crease's wedge seen from behind its wall: a ray can cross the wall, then
        // reach the floor.
        let crease = ConvexShell::of(&builtin("crease")).unwrap();
        let eye = builtin("crease").head.pose_at(0.0).position;
        let behind = eye + DVec3::new(0.0, 0.0, -1e3);
        assert!(crease.contains(eye) && !crease.contains(behind));
    }
}
