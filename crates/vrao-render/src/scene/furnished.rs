//! `builtin:furnished`: a closed, furnished room whose details are the cases screen-space
//! AO gets wrong or finds hard: thin legs (a table's, chairs'), a thin table top and thin
//! wall shelves (thin occluders that a depth buffer sees as walls), a slatted blind of
//! millimetre slats a few centimetres apart in front of a window recess (fine repeated
//! detail, depth edges everywhere), the room's wall–floor and wall–ceiling corners and a
//! skirting board (concave corners whose occlusion is known).
//!
//! Like `room`, the shell's normals face in and nothing outside it can be seen; a point
//! light hangs under the ceiling and the default sky at [`FURNISHED_AMBIENT`] stands in for
//! light bounced around the room. Every object is a union of closed boxes, so every
//! triangle is counter-clockwise seen from the side its normal points to. Units are
//! metres, +Y up; the front wall (z = 0) is behind the viewer.

use super::builtin::{cuboid_faces, eye_at, Builder, Face};
use super::{Environment, HeadPath, Light, Material, Mesh, Scene};
use glam::{DVec3, Vec3};

/// The room's inside: 5 m wide (x), 2.7 m high, 6 m deep (z from −6 to 0).
pub const FURNISHED_MIN: DVec3 = DVec3::new(-2.5, 0.0, -6.0);
/// The room's inside, upper corner (m).
pub const FURNISHED_MAX: DVec3 = DVec3::new(2.5, 2.7, 0.0);
/// The window-like recess in the back wall (z = −6): its opening spans these x and y and
/// it goes `FURNISHED_RECESS_DEPTH` into the wall, to a pale "glass" back.
pub const FURNISHED_WINDOW_MIN: [f64; 2] = [-1.6, 0.9];
/// The recess opening's upper (x, y) corner (m).
pub const FURNISHED_WINDOW_MAX: [f64; 2] = [-0.2, 2.2];
/// How far the recess goes into the back wall (m).
pub const FURNISHED_RECESS_DEPTH: f64 = 0.25;
/// Irradiance scale of the default sky standing in for bounced light.
pub const FURNISHED_AMBIENT: f32 = 0.5;
/// The ceiling point light's position (m).
pub const FURNISHED_LIGHT: DVec3 = DVec3::new(0.0, 2.3, -3.2);
/// The ceiling point light's intensity.
pub const FURNISHED_LIGHT_INTENSITY: f32 = 6.0;
/// Standing 1.7 m from the front wall, right of the middle, eyes 1.6 m up, looking past
/// the table towards the blind: the chairs' legs, the shelves, the back-left wall–floor
/// and wall–ceiling corners are in view.
pub const FURNISHED_EYE: DVec3 = DVec3::new(1.0, 1.6, -1.7);
/// The point the head looks at (m).
pub const FURNISHED_LOOK_AT: DVec3 = DVec3::new(-0.6, 0.75, -5.0);

/// The table top: 1.6 m × 0.9 m, 0.04 m thick, its upper face 0.75 m above the floor, on
/// four legs 0.05 m square.
pub const TABLE_MIN: DVec3 = DVec3::new(-1.3, 0.71, -4.3);
/// The table top's upper corner (m).
pub const TABLE_MAX: DVec3 = DVec3::new(0.3, 0.75, -3.4);
/// Side of the table's square legs (m).
pub const TABLE_LEG: f64 = 0.05;
/// The wall shelves (boards 2 cm thick, 25 cm deep) on the back wall span these x; their
/// upper faces are at these heights.
pub const SHELF_X: [f64; 2] = [0.5, 1.8];
/// Heights of the shelves' upper faces above the floor (m).
pub const SHELF_HEIGHTS: [f64; 4] = [1.0, 1.35, 1.7, 2.05];
/// Chair legs are 0.03 m square.
pub const CHAIR_LEG: f64 = 0.03;
/// Blind slats: thickness, chord (depth), vertical pitch and tilt about the x axis.
pub const SLAT_THICKNESS: f64 = 0.006;
/// Blind slat chord (depth across the slat, m).
pub const SLAT_CHORD: f64 = 0.05;
/// Vertical distance between slats (m).
pub const SLAT_PITCH: f64 = 0.035;
/// Slat tilt about the x axis (degrees).
pub const SLAT_TILT_DEG: f64 = 25.0;

const SKIRTING_HEIGHT: f64 = 0.08;
const SKIRTING_DEPTH: f64 = 0.015;

/// Material indices, in the order of [`materials`].
const WALL: usize = 0;
const FLOOR: usize = 1;
const CEILING: usize = 2;
const GLASS: usize = 3;
const WOOD: usize = 4;
const CHAIR: usize = 5;
const PAINT: usize = 6;
const BLIND: usize = 7;
const BOOKS: [usize; 3] = [8, 9, 10];

fn materials() -> Vec<Material> {
    vec![
        Material::plain("wall", Vec3::new(0.75, 0.73, 0.68)),
        Material::plain("floor", Vec3::new(0.45, 0.3, 0.18)),
        Material::plain("ceiling", Vec3::splat(0.8)),
        Material::plain("glass", Vec3::new(0.6, 0.72, 0.85)),
        Material::plain("wood", Vec3::new(0.35, 0.2, 0.1)),
        Material::plain("chair", Vec3::new(0.55, 0.12, 0.08)),
        Material::plain("paint", Vec3::splat(0.85)),
        Material::plain("blind", Vec3::new(0.85, 0.84, 0.78)),
        Material::plain("blue", Vec3::new(0.1, 0.2, 0.6)),
        Material::plain("green", Vec3::new(0.15, 0.5, 0.2)),
        Material::plain("yellow", Vec3::new(0.8, 0.65, 0.1)),
    ]
}

/// Builds `builtin:furnished`.
pub(super) fn furnished() -> Scene {
    let mut meshes = shell();
    meshes.push(skirting());
    meshes.push(table());
    meshes.push(chairs());
    meshes.extend(shelves());
    meshes.push(blind());
    Scene {
        nodes: Vec::new(),
        name: "furnished".into(),
        meshes,
        materials: materials(),
        lights: vec![Light::Point {
            position: FURNISHED_LIGHT,
            color: Vec3::ONE,
            intensity: FURNISHED_LIGHT_INTENSITY,
        }],
        environment: Some(Environment { intensity: FURNISHED_AMBIENT, ..Environment::default_sky() }),
        head: HeadPath::fixed(eye_at(FURNISHED_EYE, FURNISHED_LOOK_AT)),
    }
}

/// A parallelogram face from `corner` spanned by `u` and `v` (normal u × v).
fn quad(corner: DVec3, u: DVec3, v: DVec3) -> Face {
    Face { corner, u, v }
}

/// The walls, floor and ceiling facing in, the back wall with the window recess.
fn shell() -> Vec<Mesh> {
    let (lo, hi) = (FURNISHED_MIN, FURNISHED_MAX);
    let [left, right, floor, ceiling, _back, front] = cuboid_faces(lo, hi).map(|f| f.flipped());
    let mesh = |name: &str, faces: &[Face], material: usize| {
        let mut b = Builder::default();
        faces.iter().for_each(|f| b.face(f, 6));
        b.finish(name, material)
    };
    // The back wall (z = lo.z, facing +Z) around the opening, and the recess behind it.
    let ([x0, y0], [x1, y1]) = (FURNISHED_WINDOW_MIN, FURNISHED_WINDOW_MAX);
    let (z, d) = (lo.z, FURNISHED_RECESS_DEPTH);
    let (x, y) = (DVec3::X, DVec3::Y);
    let at = |px: f64, py: f64, pz: f64| DVec3::new(px, py, pz);
    let back = [
        quad(at(lo.x, lo.y, z), x * (hi.x - lo.x), y * (y0 - lo.y)),
        quad(at(lo.x, y1, z), x * (hi.x - lo.x), y * (hi.y - y1)),
        quad(at(lo.x, y0, z), x * (x0 - lo.x), y * (y1 - y0)),
        quad(at(x1, y0, z), x * (hi.x - x1), y * (y1 - y0)),
    ];
    let depth = DVec3::Z * d;
    let recess = [
        quad(at(x0, y0, z - d), y * (y1 - y0), depth),
        quad(at(x1, y0, z - d), depth, y * (y1 - y0)),
        quad(at(x0, y0, z - d), depth, x * (x1 - x0)),
        quad(at(x0, y1, z - d), x * (x1 - x0), depth),
    ];
    vec![
        mesh("walls", &[left, right, front], WALL),
        mesh("back wall", &back, WALL),
        mesh("recess", &recess, WALL),
        mesh("window", &[quad(at(x0, y0, z - d), x * (x1 - x0), y * (y1 - y0))], GLASS),
        mesh("floor", &[floor], FLOOR),
        mesh("ceiling", &[ceiling], CEILING),
    ]
}

/// A skirting board along the foot of all four walls.
fn skirting() -> Mesh {
    let (lo, hi, h, t) = (FURNISHED_MIN, FURNISHED_MAX, SKIRTING_HEIGHT, SKIRTING_DEPTH);
    let mut b = Builder::default();
    b.cuboid(DVec3::new(lo.x, 0.0, lo.z), DVec3::new(hi.x, h, lo.z + t));
    b.cuboid(DVec3::new(lo.x, 0.0, hi.z - t), DVec3::new(hi.x, h, hi.z));
    b.cuboid(DVec3::new(lo.x, 0.0, lo.z + t), DVec3::new(lo.x + t, h, hi.z - t));
    b.cuboid(DVec3::new(hi.x - t, 0.0, lo.z + t), DVec3::new(hi.x, h, hi.z - t));
    b.finish("skirting", PAINT)
}

fn table() -> Mesh {
    let (lo, hi, leg) = (TABLE_MIN, TABLE_MAX, TABLE_LEG);
    let mut b = Builder::default();
    b.cuboid(lo, hi);
    let inset = 0.06;
    for x in [lo.x + inset, hi.x - inset - leg] {
        for z in [lo.z + inset, hi.z - inset - leg] {
            b.cuboid(DVec3::new(x, 0.0, z), DVec3::new(x + leg, lo.y, z + leg));
        }
    }
    b.finish("table", WOOD)
}

/// Three chairs: in front of the table, behind it, and pulled out and turned at its end.
fn chairs() -> Mesh {
    let mut b = Builder::default();
    chair(&mut b, DVec3::new(-0.8, 0.0, -3.05), 180.0);
    chair(&mut b, DVec3::new(-0.3, 0.0, -4.65), 0.0);
    chair(&mut b, DVec3::new(0.85, 0.0, -3.7), -70.0);
    b.finish("chairs", CHAIR)
}

/// One chair whose seat is centred over `foot` (on the floor), its sitter facing the
/// direction `yaw_deg` turned about +Y from +Z: a 0.42 m square seat 0.45 m high, four
/// legs, the back two rising as posts to 0.9 m with a back board between them.
fn chair(b: &mut Builder, foot: DVec3, yaw_deg: f64) {
    let yaw = yaw_deg.to_radians();
    let facing = DVec3::new(yaw.sin(), 0.0, yaw.cos());
    let right = facing.cross(DVec3::Y);
    let behind = -facing;
    // A box in the chair's frame: `min` and `size` along (right, up, behind) from `foot`;
    // that frame is right-handed (right × up = behind).
    let mut part = |min: [f64; 3], size: [f64; 3]| {
        let corner = foot + right * min[0] + DVec3::Y * min[1] + behind * min[2];
        b.parallelepiped(corner, right * size[0], DVec3::Y * size[1], behind * size[2]);
    };
    let (half, leg) = (0.21, CHAIR_LEG);
    let (seat_bottom, seat_top, back_top) = (0.42, 0.45, 0.9);
    part([-half, seat_bottom, -half], [2.0 * half, seat_top - seat_bottom, 2.0 * half]);
    for x in [-half + 0.01, half - 0.01 - leg] {
        part([x, 0.0, -half + 0.01], [leg, seat_bottom, leg]);
        part([x, 0.0, half - 0.01 - leg], [leg, back_top, leg]);
    }
    let inner = half - 0.01 - leg;
    part([-inner, 0.62, half - 0.01 - 0.02], [2.0 * inner, 0.24, 0.02]);
}

/// Four thin shelves on the back wall (z = −6), right of the window, with upright books
/// and small boxes on them.
fn shelves() -> Vec<Mesh> {
    let wall = FURNISHED_MIN.z;
    let (x0, x1, depth, board) = (SHELF_X[0], SHELF_X[1], 0.25, 0.02);
    let mut boards = Builder::default();
    let mut books: Vec<Builder> = BOOKS.iter().map(|_| Builder::default()).collect();
    for (k, y) in SHELF_HEIGHTS.into_iter().enumerate() {
        boards.cuboid(DVec3::new(x0, y - board, wall), DVec3::new(x1, y, wall + depth));
        // Upright books of varied widths and heights, then a gap, then a small box.
        let mut x = x0 + 0.05 + 0.07 * k as f64;
        for i in 0..7 {
            let n = k * 7 + i;
            let width = 0.025 + 0.01 * ((n * 5) % 4) as f64;
            let height = 0.15 + 0.03 * ((n * 3) % 5) as f64;
            let min = DVec3::new(x, y, wall + 0.02);
            books[n % 3].cuboid(min, min + DVec3::new(width, height, 0.18));
            x += width + 0.004;
        }
        let side = 0.08 + 0.03 * (k % 2) as f64;
        let min = DVec3::new(x1 - 0.12 - side, y, wall + 0.05);
        books[(k + 1) % 3].cuboid(min, min + DVec3::splat(side));
    }
    let mut meshes = vec![boards.finish("shelves", PAINT)];
    for (i, b) in books.into_iter().enumerate() {
        meshes.push(b.finish(&format!("books {i}"), BOOKS[i]));
    }
    meshes
}

/// A slatted blind hanging in front of the window recess: a head rail on the wall above
/// it, thin slats tilted about x, two cords and a bottom rail.
fn blind() -> Mesh {
    let ([x0, y0], [x1, y1]) = (FURNISHED_WINDOW_MIN, FURNISHED_WINDOW_MAX);
    let (left, right) = (x0 - 0.08, x1 + 0.08);
    let z = FURNISHED_MIN.z + 0.04; // the slats' centre line, in front of the wall
    let mut b = Builder::default();
    b.cuboid(DVec3::new(left - 0.01, y1 + 0.02, FURNISHED_MIN.z), DVec3::new(right + 0.01, y1 + 0.07, z + 0.03));
    let tilt = SLAT_TILT_DEG.to_radians();
    // A slat's thickness and chord directions: +Y and +Z turned about +X.
    let (up, chord) = (DVec3::new(0.0, tilt.cos(), tilt.sin()), DVec3::new(0.0, -tilt.sin(), tilt.cos()));
    let width = DVec3::X * (right - left);
    let mut y = y1;
    while y > y0 {
        let centre = DVec3::new(left, y, z);
        b.parallelepiped(
            centre - up * (0.5 * SLAT_THICKNESS) - chord * (0.5 * SLAT_CHORD),
            width,
            up * SLAT_THICKNESS,
            chord * SLAT_CHORD,
        );
        y -= SLAT_PITCH;
    }
    b.cuboid(DVec3::new(left, y - 0.01, z - 0.015), DVec3::new(right, y + 0.01, z + 0.015));
    let cord = 0.004;
    for x in [left + 0.25 * (right - left), left + 0.75 * (right - left)] {
        b.cuboid(DVec3::new(x, y, z - 0.5 * cord), DVec3::new(x + cord, y1 + 0.02, z + 0.5 * cord));
    }
    b.finish("blind", BLIND)
}
