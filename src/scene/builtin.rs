//! Procedural scenes (`builtin:NAME`) whose geometry is known exactly, so tests can state
//! their expectations analytically (an open plane has AO ≈ 1, a 90° crease a known
//! visibility, a red wall bleeds red).
//!
//! Every triangle is counter-clockwise seen from the side its normal points to; the
//! normals are exact (flat for planes, radial for the sphere). Units are metres, +Y up.

use super::{Environment, HeadPath, Light, Material, Mesh, Scene};
use crate::error::{Error, Result};
use crate::stereo::HeadPose;
use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};

/// The built-in scene names, as `builtin:NAME` or `builtin = "NAME"` in a scene file.
pub const NAMES: [&str; 5] = ["plane", "crease", "room", "sphere", "box"];

/// Half the side of the square floor of "plane", "sphere" and "box" (x, z in ±20 m).
pub const FLOOR_HALF_SIZE: f64 = 20.0;
/// "crease": the wall lies in the plane z = `CREASE_WALL_Z`, facing +Z, for
/// x in ±`CREASE_HALF_WIDTH` and y in [0, `CREASE_WALL_HEIGHT`]. The floor (y = 0, facing
/// +Y) runs from the wall to z = `CREASE_FLOOR_END_Z`, past the eye.
pub const CREASE_WALL_Z: f64 = -3.0;
pub const CREASE_HALF_WIDTH: f64 = 5.0;
pub const CREASE_WALL_HEIGHT: f64 = 5.0;
pub const CREASE_FLOOR_END_Z: f64 = 5.0;
/// "crease": the eye, looking at the middle of the crease line (0, 0, `CREASE_WALL_Z`).
pub const CREASE_EYE: DVec3 = DVec3::new(0.0, 1.2, 0.0);
/// "sphere": a sphere resting on the floor.
pub const SPHERE_CENTER: DVec3 = DVec3::new(0.0, 1.0, 0.0);
pub const SPHERE_RADIUS: f64 = 1.0;
/// "room": the inside of a closed box, normals facing in. The −X wall is red, the +X wall
/// green, the rest white; a 0.8 m cube stands on the floor; a point light hangs below the
/// ceiling. Being closed, nothing outside can be seen; the default sky at
/// `ROOM_AMBIENT` intensity stands in for the light bounced around the room, so the
/// ambient term (what occlusion attenuates) is not zero.
pub const ROOM_AMBIENT: f32 = 0.5;
pub const ROOM_MIN: DVec3 = DVec3::new(-2.0, 0.0, -4.0);
pub const ROOM_MAX: DVec3 = DVec3::new(2.0, 3.0, 0.0);
pub const ROOM_BOX_MIN: DVec3 = DVec3::new(0.0, 0.0, -3.0);
pub const ROOM_BOX_MAX: DVec3 = DVec3::new(0.8, 0.8, -2.2);
pub const ROOM_LIGHT: DVec3 = DVec3::new(0.0, 2.7, -2.0);

const WHITE: f32 = 0.8;
const ROOM_WHITE: f32 = 0.75;

/// The names of the built-in scenes.
pub fn names() -> &'static [&'static str] {
    &NAMES
}

/// Builds the built-in scene `name`.
pub fn load(name: &str) -> Result<Scene> {
    let scene = match name {
        "plane" => open_scene(name, vec![floor()], eye_at(DVec3::new(0.0, 1.6, 0.0), DVec3::new(0.0, 0.0, -3.0))),
        "crease" => crease(),
        "room" => room(),
        "sphere" => {
            let mut ball = Builder::default();
            ball.sphere(SPHERE_CENTER, SPHERE_RADIUS, 48, 96);
            let meshes = vec![floor(), ball.finish("sphere", 0)];
            open_scene(name, meshes, eye_at(DVec3::new(0.0, 1.6, 4.0), SPHERE_CENTER))
        }
        "box" => {
            let mut cube = Builder::default();
            cuboid_faces(DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 1.0, 0.5)).iter().for_each(|f| cube.face(f, 1));
            let meshes = vec![floor(), cube.finish("box", 0)];
            open_scene(name, meshes, eye_at(DVec3::new(1.5, 1.6, 3.0), DVec3::new(0.0, 0.5, 0.0)))
        }
        _ => {
            return Err(Error::input(format!("unknown builtin scene '{name}'; available: {}", NAMES.join(", "))));
        }
    };
    Ok(scene)
}

/// An outdoor scene: white materials, the default sun and the default sky.
fn open_scene(name: &str, meshes: Vec<Mesh>, head: HeadPose) -> Scene {
    Scene {
        name: name.into(),
        meshes,
        materials: vec![Material::plain("white", Vec3::splat(WHITE))],
        lights: vec![Light::default_sun()],
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(head),
    }
}

fn eye_at(eye: DVec3, target: DVec3) -> HeadPose {
    // The eyes and targets above are distinct constants.
    HeadPose::look_at(eye, target).expect("built-in eye and target differ")
}

/// The 40 m × 40 m floor at y = 0, split into 8×8 quads.
fn floor() -> Mesh {
    let (h, side) = (FLOOR_HALF_SIZE, 2.0 * FLOOR_HALF_SIZE);
    let mut b = Builder::default();
    b.face(&Face { corner: DVec3::new(-h, 0.0, -h), u: DVec3::Z * side, v: DVec3::X * side }, 8);
    b.finish("floor", 0)
}

fn crease() -> Scene {
    let width = 2.0 * CREASE_HALF_WIDTH;
    let corner = DVec3::new(-CREASE_HALF_WIDTH, 0.0, CREASE_WALL_Z);
    let mut floor = Builder::default();
    floor.face(&Face { corner, u: DVec3::Z * (CREASE_FLOOR_END_Z - CREASE_WALL_Z), v: DVec3::X * width }, 8);
    let mut wall = Builder::default();
    wall.face(&Face { corner, u: DVec3::X * width, v: DVec3::Y * CREASE_WALL_HEIGHT }, 8);
    let meshes = vec![floor.finish("floor", 0), wall.finish("wall", 0)];
    open_scene("crease", meshes, eye_at(CREASE_EYE, DVec3::new(0.0, 0.0, CREASE_WALL_Z)))
}

fn room() -> Scene {
    let walls = cuboid_faces(ROOM_MIN, ROOM_MAX).map(|f| f.flipped());
    let mesh = |name: &str, faces: &[Face], material: usize| {
        let mut b = Builder::default();
        faces.iter().for_each(|f| b.face(f, 4));
        b.finish(name, material)
    };
    let [left, right, floor, ceiling, back, front] = walls;
    let meshes = vec![
        mesh("walls", &[floor, ceiling, back, front], 0),
        mesh("left wall", &[left], 1),
        mesh("right wall", &[right], 2),
        mesh("box", &cuboid_faces(ROOM_BOX_MIN, ROOM_BOX_MAX), 0),
    ];
    let box_centre = (ROOM_BOX_MIN + ROOM_BOX_MAX) * 0.5;
    Scene {
        name: "room".into(),
        meshes,
        materials: vec![
            Material::plain("white", Vec3::splat(ROOM_WHITE)),
            Material::plain("red", Vec3::new(0.75, 0.1, 0.1)),
            Material::plain("green", Vec3::new(0.1, 0.75, 0.1)),
        ],
        lights: vec![Light::Point { position: ROOM_LIGHT, color: Vec3::ONE, intensity: 6.0 }],
        environment: Some(Environment { intensity: ROOM_AMBIENT, ..Environment::default_sky() }),
        // Standing with the front wall (z = 0) at our back, looking at the box.
        head: HeadPath::fixed(eye_at(DVec3::new(0.0, 1.6, -0.4), box_centre)),
    }
}

/// A parallelogram from `corner` spanned by `u` and `v`; its normal is u × v.
#[derive(Clone, Copy, Debug)]
struct Face {
    corner: DVec3,
    u: DVec3,
    v: DVec3,
}

impl Face {
    /// The same face seen from the other side.
    fn flipped(self) -> Face {
        Face { u: self.v, v: self.u, ..self }
    }
}

/// The six faces of an axis-aligned box, normals outward, in the order −X, +X, −Y, +Y,
/// −Z, +Z.
fn cuboid_faces(min: DVec3, max: DVec3) -> [Face; 6] {
    let s = max - min;
    let (x, y, z) = (DVec3::X * s.x, DVec3::Y * s.y, DVec3::Z * s.z);
    [
        Face { corner: min, u: z, v: y },
        Face { corner: min + x, u: y, v: z },
        Face { corner: min, u: x, v: z },
        Face { corner: min + y, u: z, v: x },
        Face { corner: min, u: y, v: x },
        Face { corner: min + z, u: x, v: y },
    ]
}

/// Accumulates world-space vertices and triangles for one mesh.
#[derive(Default)]
struct Builder {
    positions: Vec<DVec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

impl Builder {
    /// `face` as an n×n grid of quads, each split into two CCW triangles.
    fn face(&mut self, face: &Face, n: u32) {
        let normal = face.u.cross(face.v).normalize().as_vec3();
        let base = self.positions.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                self.positions.push(face.corner + face.u * (i as f64 / n as f64) + face.v * (j as f64 / n as f64));
                self.normals.push(normal);
            }
        }
        self.grid(base, n, n);
    }

    /// A UV sphere with radial normals: `rings` bands from +Y to −Y, `segments` around.
    fn sphere(&mut self, centre: DVec3, radius: f64, rings: u32, segments: u32) {
        let base = self.positions.len() as u32;
        for r in 0..=rings {
            let theta = PI * r as f64 / rings as f64;
            for s in 0..=segments {
                let phi = TAU * s as f64 / segments as f64;
                let dir = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                self.positions.push(centre + dir * radius);
                self.normals.push(dir.as_vec3());
            }
        }
        self.grid(base, segments, rings);
        // The pole rows collapse to points: drop the zero-area triangles they make.
        let positions = &self.positions;
        let area = |t: &[u32]| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            (b - a).cross(c - a).length()
        };
        self.indices = self.indices.chunks(3).filter(|t| area(t) > 1e-12).flatten().copied().collect();
    }

    /// Triangles for a (nu+1)×(nv+1) vertex grid starting at `base`, row-major in u.
    /// Vertex (i, j) sits at corner + u·i/nu + v·j/nv, so each quad's triangles are CCW
    /// seen from the u × v side.
    fn grid(&mut self, base: u32, nu: u32, nv: u32) {
        let row = nu + 1;
        for j in 0..nv {
            for i in 0..nu {
                let a = base + j * row + i;
                self.indices.extend([a, a + 1, a + row + 1, a, a + row + 1, a + row]);
            }
        }
    }

    fn finish(self, name: &str, material: usize) -> Mesh {
        let (origin, positions) = Mesh::recentre(&self.positions);
        Mesh {
            name: name.into(),
            origin,
            uvs: vec![glam::Vec2::ZERO; positions.len()],
            positions,
            normals: self.normals,
            indices: self.indices,
            material,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_has_unit_normals_that_agree_with_winding() {
        for name in names() {
            let scene = load(name).unwrap();
            assert_eq!(scene.name, *name);
            for m in &scene.meshes {
                assert!(m.material < scene.materials.len());
                assert_eq!(m.normals.len(), m.positions.len());
                assert_eq!(m.uvs.len(), m.positions.len());
                assert!(!m.indices.is_empty() && m.indices.len() % 3 == 0);
                for n in &m.normals {
                    assert!((n.length() - 1.0).abs() < 1e-5, "{name}/{}: normal {n}", m.name);
                }
                for t in m.indices.chunks(3) {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                    let face = (b - a).cross(c - a).normalize();
                    for &i in t {
                        let agreement = face.dot(m.normals[i as usize]);
                        assert!(agreement > 0.95, "{name}/{}: winding disagrees with normal ({agreement})", m.name);
                    }
                }
            }
        }
    }

    #[test]
    fn crease_geometry_matches_its_constants() {
        let scene = load("crease").unwrap();
        let b = scene.bounds();
        assert_eq!(b.min, DVec3::new(-CREASE_HALF_WIDTH, 0.0, CREASE_WALL_Z));
        assert_eq!(b.max, DVec3::new(CREASE_HALF_WIDTH, CREASE_WALL_HEIGHT, CREASE_FLOOR_END_Z));
        let [floor, wall] = [&scene.meshes[0], &scene.meshes[1]];
        assert!(floor.normals.iter().all(|n| *n == Vec3::Y));
        assert!(wall.normals.iter().all(|n| *n == Vec3::Z));
        assert!(wall.positions.iter().all(|p| wall.origin.z + p.z as f64 == CREASE_WALL_Z));
        assert_eq!(scene.head.keys[0].1.position, CREASE_EYE);
    }

    #[test]
    fn room_is_closed_and_faces_inward() {
        let scene = load("room").unwrap();
        assert_eq!(scene.environment.as_ref().map(|e| e.intensity), Some(ROOM_AMBIENT));
        let bounds = scene.bounds();
        assert!(bounds.min.abs_diff_eq(ROOM_MIN, 1e-6) && bounds.max.abs_diff_eq(ROOM_MAX, 1e-6), "{bounds:?}");
        let centre = (ROOM_MIN + ROOM_MAX) * 0.5;
        let walls: Vec<&Mesh> = scene.meshes.iter().filter(|m| m.name != "box").collect();
        let mut axes_seen = Vec::new();
        for m in walls {
            for (p, n) in m.positions.iter().zip(&m.normals) {
                let to_centre = centre - (m.origin + p.as_dvec3());
                assert!(n.as_dvec3().dot(to_centre) > 0.0, "{} faces outward", m.name);
                axes_seen.push(n.to_array().map(|c| c as i32));
            }
        }
        axes_seen.sort();
        axes_seen.dedup();
        assert_eq!(axes_seen.len(), 6, "six walls");
        let red = scene.meshes.iter().find(|m| m.name == "left wall").unwrap();
        assert_eq!(scene.materials[red.material].diffuse, Vec3::new(0.75, 0.1, 0.1));
        assert!(red.normals.iter().all(|n| *n == Vec3::X), "the −X wall faces +X");
    }

    #[test]
    fn sphere_rests_on_the_floor() {
        let scene = load("sphere").unwrap();
        let ball = &scene.meshes[1];
        for (p, n) in ball.positions.iter().zip(&ball.normals) {
            let world = ball.origin + p.as_dvec3();
            assert!(((world - SPHERE_CENTER).length() - SPHERE_RADIUS).abs() < 1e-6);
            assert!(n.as_dvec3().dot((world - SPHERE_CENTER).normalize()) > 0.999_99);
        }
        assert!((scene.bounds().min.y).abs() < 1e-9);
    }

    #[test]
    fn unknown_name_lists_the_choices() {
        let err = load("teapot").unwrap_err().to_string();
        assert!(err.contains("teapot") && NAMES.iter().all(|n| err.contains(n)), "{err}");
    }
}
