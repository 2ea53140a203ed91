//! Procedural scenes (`builtin:NAME`) whose geometry is known exactly, so tests can state
//! their expectations analytically (an open plane has AO ≈ 1, a 90° crease a known
//! visibility, a red wall bleeds red).
//!
//! Every triangle is counter-clockwise seen from the side its normal points to; the
//! normals are exact (flat for planes, radial for the sphere), except in
//! `flipped-normals`, whose normals are wrong on purpose. Units are metres, +Y up.
//! `furnished` (`furnished.rs`), `columns` and `flipped-normals` (`edge_cases.rs`) show
//! screen-space AO's failure modes.

use super::{Environment, HeadPath, Light, Material, Mesh, Scene};
use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};
use vrao_ao::{Error, HeadPose, Result};

/// The built-in scene names, as `builtin:NAME` or `builtin = "NAME"` in a scene file.
pub const NAMES: [&str; 10] =
    ["plane", "crease", "room", "sphere", "box", "furnished", "columns", "flipped-normals", "grille", "moving"];

/// Half the side of the square floor of "plane", "sphere" and "box" (x, z in ±20 m).
pub const FLOOR_HALF_SIZE: f64 = 20.0;
/// "crease": the wall lies in the plane z = `CREASE_WALL_Z`, facing +Z, for
/// x in ±`CREASE_HALF_WIDTH` and y in [0, `CREASE_WALL_HEIGHT`]. The floor (y = 0, facing
/// +Y) runs from the wall to z = `CREASE_FLOOR_END_Z`, past the eye.
pub const CREASE_WALL_Z: f64 = -3.0;
/// "crease": half the wall's width along x (m).
pub const CREASE_HALF_WIDTH: f64 = 5.0;
/// "crease": the wall's height (m).
pub const CREASE_WALL_HEIGHT: f64 = 5.0;
/// "crease": z where the floor ends, behind the eye (m).
pub const CREASE_FLOOR_END_Z: f64 = 5.0;
/// "crease": the eye, looking at the middle of the crease line (0, 0, `CREASE_WALL_Z`).
pub const CREASE_EYE: DVec3 = DVec3::new(0.0, 1.2, 0.0);
/// "sphere": a sphere resting on the floor.
pub const SPHERE_CENTER: DVec3 = DVec3::new(0.0, 1.0, 0.0);
/// "sphere": its radius (m), so it touches the floor at the origin.
pub const SPHERE_RADIUS: f64 = 1.0;
/// "room": the inside of a closed box, normals facing in. The −X wall is red, the +X wall
/// green, the rest white; a 0.8 m cube stands on the floor; a point light hangs below the
/// ceiling. Being closed, nothing outside can be seen; the default sky at
/// `ROOM_AMBIENT` intensity stands in for the light bounced around the room, so the
/// ambient term (what occlusion attenuates) is not zero.
pub const ROOM_AMBIENT: f32 = 0.5;
/// "room": the inside's lower corner (m).
pub const ROOM_MIN: DVec3 = DVec3::new(-2.0, 0.0, -4.0);
/// "room": the inside's upper corner (m).
pub const ROOM_MAX: DVec3 = DVec3::new(2.0, 3.0, 0.0);
/// "room": the cube's lower corner (m).
pub const ROOM_BOX_MIN: DVec3 = DVec3::new(0.0, 0.0, -3.0);
/// "room": the cube's upper corner (m).
pub const ROOM_BOX_MAX: DVec3 = DVec3::new(0.8, 0.8, -2.2);
/// "room": the point light's position (m).
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
        "furnished" => super::furnished::furnished(),
        "columns" => super::edge_cases::columns(),
        "flipped-normals" => super::edge_cases::flipped_normals(),
        "grille" => super::content::grille(),
        "moving" => super::content::moving(),
        _ => {
            return Err(Error::input(format!("unknown builtin scene '{name}'; available: {}", NAMES.join(", "))));
        }
    };
    Ok(scene)
}

/// An outdoor scene: white materials, the default sun and the default sky.
pub(super) fn open_scene(name: &str, meshes: Vec<Mesh>, head: HeadPose) -> Scene {
    Scene {
        nodes: Vec::new(),
        name: name.into(),
        meshes,
        materials: vec![Material::plain("white", Vec3::splat(WHITE))],
        lights: vec![Light::default_sun()],
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(head),
    }
}

pub(super) fn eye_at(eye: DVec3, target: DVec3) -> HeadPose {
    // The eyes and targets above are distinct constants.
    HeadPose::look_at(eye, target).expect("built-in eye and target differ")
}

/// The 40 m × 40 m floor at y = 0, split into 8×8 quads.
pub(super) fn floor() -> Mesh {
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
        nodes: Vec::new(),
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
pub(super) struct Face {
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
}

impl Face {
    /// The same face seen from the other side.
    pub(super) fn flipped(self) -> Face {
        Face { u: self.v, v: self.u, ..self }
    }
}

/// The six faces of an axis-aligned box, normals outward, in the order −X, +X, −Y, +Y,
/// −Z, +Z.
pub(super) fn cuboid_faces(min: DVec3, max: DVec3) -> [Face; 6] {
    let s = max - min;
    parallelepiped_faces(min, DVec3::X * s.x, DVec3::Y * s.y, DVec3::Z * s.z)
}

/// The six faces of the parallelepiped at `corner` with edges `x`, `y`, `z` (a
/// right-handed set: (x × y) · z > 0), normals outward, in the order −x, +x, −y, +y, −z, +z.
pub(super) fn parallelepiped_faces(corner: DVec3, x: DVec3, y: DVec3, z: DVec3) -> [Face; 6] {
    [
        Face { corner, u: z, v: y },
        Face { corner: corner + x, u: y, v: z },
        Face { corner, u: x, v: z },
        Face { corner: corner + y, u: z, v: x },
        Face { corner, u: y, v: x },
        Face { corner: corner + z, u: x, v: y },
    ]
}

/// Accumulates world-space vertices and triangles for one mesh.
#[derive(Default)]
pub(super) struct Builder {
    positions: Vec<DVec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

impl Builder {
    /// `face` as an n×n grid of quads, each split into two CCW triangles.
    pub(super) fn face(&mut self, face: &Face, n: u32) {
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

    /// An axis-aligned box, normals outward, one quad a face.
    pub(super) fn cuboid(&mut self, min: DVec3, max: DVec3) {
        cuboid_faces(min, max).iter().for_each(|f| self.face(f, 1));
    }

    /// The parallelepiped at `corner` with right-handed edges `x`, `y`, `z` (a turned box),
    /// normals outward, one quad a face.
    pub(super) fn parallelepiped(&mut self, corner: DVec3, x: DVec3, y: DVec3, z: DVec3) {
        parallelepiped_faces(corner, x, y, z).iter().for_each(|f| self.face(f, 1));
    }

    /// An upright closed cylinder standing on `base` (the centre of its bottom disc):
    /// radial normals on the side, flat caps.
    pub(super) fn cylinder(&mut self, base: DVec3, radius: f64, height: f64, segments: u32) {
        // Angle φ runs from +X towards −Z, so the side's grid (u around, v up) faces out.
        let rim = |i: u32| {
            let phi = TAU * i as f64 / segments as f64;
            DVec3::new(phi.cos(), 0.0, -phi.sin())
        };
        let side = self.positions.len() as u32;
        for j in 0..=1 {
            for i in 0..=segments {
                self.positions.push(base + rim(i) * radius + DVec3::Y * (height * j as f64));
                self.normals.push(rim(i).as_vec3());
            }
        }
        self.grid(side, segments, 1);
        for (y, normal) in [(0.0, Vec3::NEG_Y), (height, Vec3::Y)] {
            let centre = self.positions.len() as u32;
            self.positions.push(base + DVec3::Y * y);
            self.normals.push(normal);
            for i in 0..segments {
                self.positions.push(base + rim(i) * radius + DVec3::Y * y);
                self.normals.push(normal);
            }
            for i in 0..segments {
                let (a, b) = (centre + 1 + i, centre + 1 + (i + 1) % segments);
                // Seen from above the rim runs counter-clockwise, so the top keeps its
                // order and the bottom reverses it.
                self.indices.extend(if normal == Vec3::Y { [centre, a, b] } else { [centre, b, a] });
            }
        }
    }

    /// A UV sphere with radial normals: `rings` bands from +Y to −Y, `segments` around.
    pub(super) fn sphere(&mut self, centre: DVec3, radius: f64, rings: u32, segments: u32) {
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

    pub(super) fn finish(self, name: &str, material: usize) -> Mesh {
        let (origin, positions) = Mesh::recentre(&self.positions);
        Mesh {
            colors: Vec::new(),
            tangents: Vec::new(),
            name: name.into(),
            origin,
            node: None,
            uvs: vec![glam::Vec2::ZERO; positions.len()],
            uvs1: Vec::new(),
            positions,
            normals: self.normals,
            indices: self.indices,
            material,
        }
    }
}

#[cfg(test)]
mod tests;
