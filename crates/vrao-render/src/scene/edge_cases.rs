//! Built-in scenes for two of screen-space AO's failure modes (the third, a furnished
//! room, is `furnished.rs`):
//!
//! - `columns`: depth-edge halos and thin occluders outdoors. Round and square columns, a
//!   thin pole and a wall with doorways stand on an open floor, seen so that far floor
//!   and wall lie right beside the near columns' silhouettes (where a depth buffer jumps);
//!   a slab floats above the floor (a thin occluder with light under it); boxes, a bench
//!   and a ball stand on the floor (contact lines).
//! - `flipped-normals`: the sphere on the floor with bad normals: scattered vertices'
//!   normals point into the ball, and vertices along the upper silhouette have normals
//!   turned 120° from the surface's. Its geometry is right (triangles counter-clockwise
//!   seen from outside); only the normals lie. An estimator must still give no pixel AO
//!   of exactly 0 and no shaded pixel pure black.

use super::builtin::{eye_at, floor, open_scene, Builder, SPHERE_CENTER, SPHERE_RADIUS};
use super::{Material, Scene};
use glam::{DVec3, Vec3};

/// "columns": the head, standing 2 m in front of the bench, looking down the scene towards
/// the wall: far floor and wall lie beside every column.
pub const COLUMNS_EYE: DVec3 = DVec3::new(0.2, 1.6, 0.9);
/// "columns": the point the head looks at (m).
pub const COLUMNS_LOOK_AT: DVec3 = DVec3::new(-0.1, 0.8, -3.0);
/// Round columns: 0.2 m radius, 3 m tall, centred at these (x, z).
pub const COLUMN_RADIUS: f64 = 0.2;
/// Height of every round column (m).
pub const COLUMN_HEIGHT: f64 = 3.0;
/// (x, z) of each column's axis (m).
pub const COLUMN_SITES: [[f64; 2]; 4] = [[-2.2, -2.0], [-0.7, -3.6], [1.1, -2.4], [2.5, -4.6]];
/// The thin pole: 1.5 cm radius, 2.2 m tall.
pub const POLE_RADIUS: f64 = 0.015;
/// (x, z) of the thin pole's axis (m).
pub const POLE_SITE: [f64; 2] = [0.35, -1.0];
/// The floating slab, 8 cm thick, 55 cm above the floor.
pub const SLAB_MIN: DVec3 = DVec3::new(-2.4, 0.55, -1.9);
/// The floating slab's upper corner (m).
pub const SLAB_MAX: DVec3 = DVec3::new(-1.0, 0.63, -0.9);
/// The wall (x in ±6 m, 3.5 m high) runs from z = `WALL_Z` back 0.3 m; it has three
/// doorways 1.2 m wide and 2.4 m high, centred at x = −3, 0, 3.
pub const WALL_Z: f64 = -7.0;

/// "flipped-normals": the head, closer to the ball than in "sphere" (which is at 4 m), so
/// the ball fills a good part of the view.
pub const FLIPPED_EYE: DVec3 = DVec3::new(0.0, 1.6, 2.6);
/// A silhouette vertex (seen from `FLIPPED_EYE`) is one whose outward normal is within
/// this cosine of perpendicular to the line of sight.
pub const SILHOUETTE_COS: f64 = 0.08;

const STONE: usize = 1;
const RED: usize = 2;
const BLUE: usize = 3;

/// Builds `builtin:columns`.
pub(super) fn columns() -> Scene {
    let mut round = Builder::default();
    for [x, z] in COLUMN_SITES {
        round.cylinder(DVec3::new(x, 0.0, z), COLUMN_RADIUS, COLUMN_HEIGHT, 48);
    }
    let mut square = Builder::default();
    square.cuboid(DVec3::new(-1.8, 0.0, -5.6), DVec3::new(-1.4, COLUMN_HEIGHT, -5.2));
    let mut pole = Builder::default();
    pole.cylinder(DVec3::new(POLE_SITE[0], 0.0, POLE_SITE[1]), POLE_RADIUS, 2.2, 16);

    let mut wall = Builder::default();
    let (z0, z1, height, door_top) = (WALL_Z - 0.3, WALL_Z, 3.5, 2.4);
    for [x0, x1] in [[-6.0, -3.6], [-2.4, -0.6], [0.6, 2.4], [3.6, 6.0]] {
        wall.cuboid(DVec3::new(x0, 0.0, z0), DVec3::new(x1, door_top, z1));
    }
    wall.cuboid(DVec3::new(-6.0, door_top, z0), DVec3::new(6.0, height, z1));

    let mut slab = Builder::default();
    slab.cuboid(SLAB_MIN, SLAB_MAX);

    let mut boxes = Builder::default();
    boxes.cuboid(DVec3::new(0.7, 0.0, -1.0), DVec3::new(1.2, 0.5, -0.5));
    boxes.cuboid(DVec3::new(-0.36, 0.0, -0.46), DVec3::new(-0.24, 0.12, -0.34));
    let mut bench = Builder::default();
    bench.cuboid(DVec3::new(-0.9, 0.0, -2.2), DVec3::new(0.1, 0.4, -1.8));
    let mut ball = Builder::default();
    ball.sphere(DVec3::new(1.6, 0.3, -1.7), 0.3, 24, 48);

    let meshes = vec![
        floor(),
        round.finish("round columns", STONE),
        square.finish("square column", STONE),
        pole.finish("pole", BLUE),
        wall.finish("wall", STONE),
        slab.finish("slab", RED),
        boxes.finish("boxes", RED),
        bench.finish("bench", BLUE),
        ball.finish("ball", 0),
    ];
    let mut scene = open_scene("columns", meshes, eye_at(COLUMNS_EYE, COLUMNS_LOOK_AT));
    scene.materials.extend([
        Material::plain("stone", Vec3::new(0.7, 0.66, 0.58)),
        Material::plain("red", Vec3::new(0.7, 0.3, 0.2)),
        Material::plain("blue", Vec3::new(0.2, 0.35, 0.7)),
    ]);
    debug_assert_eq!(scene.materials.len(), BLUE + 1);
    scene
}

/// True for about one vertex index in 64, spread irregularly (a Weyl sequence's
/// fractional part below 1/64).
fn scattered(index: usize) -> bool {
    (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 58 == 0
}

/// Builds `builtin:flipped-normals`.
pub(super) fn flipped_normals() -> Scene {
    let mut b = Builder::default();
    // Coarser than "sphere" (48 × 96) so that each bad normal spreads over a visible patch.
    b.sphere(SPHERE_CENTER, SPHERE_RADIUS, 32, 64);
    let mut ball = b.finish("ball", 0);
    for (i, n) in ball.normals.iter_mut().enumerate() {
        let p = ball.origin + ball.positions[i].as_dvec3();
        let outward = (p - SPHERE_CENTER) / SPHERE_RADIUS;
        let to_eye = (FLIPPED_EYE - p).normalize();
        let facing = outward.dot(to_eye);
        if facing.abs() < SILHOUETTE_COS && p.y > SPHERE_CENTER.y {
            // Turned 120° from the surface normal: on the left half towards the viewer
            // (but into the ball), on the right half away from the viewer.
            let towards_eye = (to_eye - outward * facing).normalize();
            let side = if p.x < 0.0 { 1.0 } else { -1.0 };
            let turned = -0.5 * outward + side * 0.75f64.sqrt() * towards_eye;
            *n = turned.normalize().as_vec3();
        } else if scattered(i) {
            *n = -*n;
        }
    }
    open_scene("flipped-normals", vec![floor(), ball], eye_at(FLIPPED_EYE, SPHERE_CENTER))
}
