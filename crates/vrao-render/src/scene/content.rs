//! Built-in scenes that show what real content adds: `grille`, an alpha-tested checker
//! plate over a floor (its holes must be holes for every pass and for the reference
//! tracer), and `moving`, a ball rolling past a wall and a door swinging on its hinge
//! (moving objects near contact: motion vectors and the AO they cast).

use super::builtin::{cuboid_faces, eye_at, Builder, Face};
use super::{
    AlphaMode, Environment, HeadPath, Interpolation, Light, Material, Mesh, Node, NodeTracks, Scene, Texture, Track,
    Trs,
};
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};

/// "grille": the plate's height above the floor (m).
pub const GRILLE_HEIGHT: f64 = 0.25;
/// "grille": half the plate's side (m); it spans x and z in ±this.
pub const GRILLE_HALF_SIZE: f64 = 1.0;
/// "grille": checker cells along each side; cell (i, j) is a hole when i + j is odd.
pub const GRILLE_CELLS: u32 = 8;
/// "grille": half the side of its floor (m).
const GRILLE_FLOOR_HALF: f64 = 3.0;
/// Texels per checker cell of the grille's mask.
const TEXELS_PER_CELL: u32 = 8;

/// Whether the grille's plate is solid above floor point (x, z) (`None` outside it).
pub fn grille_solid_at(x: f64, z: f64) -> Option<bool> {
    let h = GRILLE_HALF_SIZE;
    if x.abs() >= h || z.abs() >= h {
        return None;
    }
    let cell = 2.0 * h / GRILLE_CELLS as f64;
    let (i, j) = (((x + h) / cell).floor() as u32, ((z + h) / cell).floor() as u32);
    Some((i + j) % 2 == 0)
}

/// The checker mask: alpha 255 on solid cells, 0 on holes; uv (u, v) = ((x + h) / 2h,
/// (z + h) / 2h), so cell (i, j) covers texels i·8.. along u and j·8.. along v.
fn checker_texture() -> Texture {
    let side = GRILLE_CELLS * TEXELS_PER_CELL;
    let mut rgba8 = Vec::with_capacity((side * side * 4) as usize);
    for y in 0..side {
        for x in 0..side {
            let solid = (x / TEXELS_PER_CELL + y / TEXELS_PER_CELL).is_multiple_of(2);
            rgba8.extend([200, 200, 200, if solid { 255 } else { 0 }]);
        }
    }
    Texture { sampling: Default::default(), width: side, height: side, rgba8: rgba8.into(), source: None }
}

/// A two-sided horizontal quad at height `y` over x, z in ±`h`, with uvs as
/// [`checker_texture`] expects.
fn plate(y: f64, h: f64, material: usize) -> Mesh {
    let corners = [(-h, -h), (h, -h), (h, h), (-h, h)];
    let world: Vec<DVec3> = corners.iter().map(|&(x, z)| DVec3::new(x, y, z)).collect();
    let (origin, positions) = Mesh::recentre(&world);
    let uvs =
        corners.iter().map(|&(x, z)| Vec2::new(((x + h) / (2.0 * h)) as f32, ((z + h) / (2.0 * h)) as f32)).collect();
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: "grille".into(),
        origin,
        positions,
        normals: vec![Vec3::Y; 4],
        uvs,
        uvs1: Vec::new(),
        // Counter-clockwise seen from above (+Y).
        indices: vec![0, 2, 1, 0, 3, 2],
        material,
        node: None,
    }
}

/// The grille scene (module docs).
pub fn grille() -> Scene {
    let h = GRILLE_FLOOR_HALF;
    let mut floor = Builder::default();
    floor.face(&Face { corner: DVec3::new(-h, 0.0, -h), u: DVec3::Z * 2.0 * h, v: DVec3::X * 2.0 * h }, 4);
    let mut mask = Material::plain("grille", Vec3::splat(0.8));
    mask.diffuse_texture = Some(checker_texture());
    mask.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    Scene {
        name: "grille".into(),
        meshes: vec![floor.finish("floor", 0), plate(GRILLE_HEIGHT, GRILLE_HALF_SIZE, 1)],
        materials: vec![Material::plain("white", Vec3::splat(0.8)), mask],
        lights: vec![Light::default_sun()],
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(eye_at(DVec3::new(0.0, 1.3, 1.5), DVec3::new(0.0, 0.0, 0.0))),
        nodes: Vec::new(),
    }
}

/// "moving": the ball's radius (m).
pub const BALL_RADIUS: f64 = 0.25;
/// "moving": the ball rolls along x between ±this (m) at z = [`BALL_Z`], there and back
/// in [`MOVING_PERIOD`].
pub const BALL_TRAVEL: f64 = 1.5;
/// "moving": z of the ball's path, its surface 0.1 m from the wall at z = [`WALL_Z`].
pub const BALL_Z: f64 = WALL_Z + BALL_RADIUS + 0.1;
/// "moving": the wall's front face (facing +Z).
pub const WALL_Z: f64 = -1.0;
/// "moving": the animation's loop (s).
pub const MOVING_PERIOD: f64 = 4.0;
/// "moving": how far the door swings open (degrees), towards −x.
const DOOR_SWING_DEG: f64 = 75.0;
/// "moving": x of the door's hinge, so that the open door stops 0.4 m short of the ball's
/// path (within the AO radius: the AO between them changes as both move).
const DOOR_HINGE_X: f64 = 3.0;

/// The moving scene (module docs): the ball (node 0) rolls with linear keys, the door
/// (node 1) swings with cubic-spline keys (eased at both ends).
pub fn moving() -> Scene {
    let mut floor = Builder::default();
    floor.face(&Face { corner: DVec3::new(-4.0, 0.0, WALL_Z), u: DVec3::Z * 6.0, v: DVec3::X * 8.0 }, 4);
    let mut wall = Builder::default();
    wall.face(&Face { corner: DVec3::new(-4.0, 0.0, WALL_Z), u: DVec3::X * 8.0, v: DVec3::Y * 2.5 }, 4);
    let mut ball = Builder::default();
    ball.sphere(DVec3::ZERO, BALL_RADIUS, 24, 48);
    let mut door = Builder::default();
    // In the hinge frame: 0.9 m wide along +z, 2 m tall, 4 cm thick on the +x side (it
    // swings towards −x, into view, so nothing turns behind the hinge into the wall).
    cuboid_faces(DVec3::ZERO, DVec3::new(0.04, 2.0, 0.9)).iter().for_each(|f| door.face(f, 1));
    let mut ball = ball.finish("ball", 1);
    ball.node = Some(0);
    let mut door = door.finish("door", 2);
    door.node = Some(1);

    // The ball: there and back along x, turning about −z as it rolls (angle = distance / r).
    let keys = 40;
    let mut times = Vec::new();
    let mut positions = Vec::new();
    let mut turns = Vec::new();
    for k in 0..=keys {
        let t = MOVING_PERIOD * k as f64 / keys as f64;
        let phase = t / MOVING_PERIOD;
        let x = if phase <= 0.5 {
            -BALL_TRAVEL + 4.0 * BALL_TRAVEL * phase
        } else {
            3.0 * BALL_TRAVEL - 4.0 * BALL_TRAVEL * phase
        };
        times.push(t);
        positions.push(DVec3::new(x, BALL_RADIUS, BALL_Z));
        turns.push(DQuat::from_rotation_z(-(x + BALL_TRAVEL) / BALL_RADIUS));
    }
    let ball_node = Node {
        name: "ball".into(),
        parent: None,
        base: DMat4::IDENTITY,
        rest: Trs { translation: positions[0], ..Trs::IDENTITY },
        tracks: NodeTracks {
            translation: Some(Track { interpolation: Interpolation::Linear, times: times.clone(), values: positions }),
            rotation: Some(Track { interpolation: Interpolation::Linear, times, values: turns }),
            scale: None,
        },
    };
    // The door: shut, open, shut, with zero tangents (ease in and out).
    let open = DQuat::from_rotation_y(-DOOR_SWING_DEG.to_radians());
    let zero = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let door_node = Node {
        name: "door".into(),
        parent: None,
        base: DMat4::IDENTITY,
        rest: Trs { translation: DVec3::new(DOOR_HINGE_X, 0.0, WALL_Z + 0.02), ..Trs::IDENTITY },
        tracks: NodeTracks {
            rotation: Some(Track {
                interpolation: Interpolation::CubicSpline,
                times: vec![0.0, 0.5 * MOVING_PERIOD, MOVING_PERIOD],
                values: vec![zero, DQuat::IDENTITY, zero, zero, open, zero, zero, DQuat::IDENTITY, zero],
            }),
            ..Default::default()
        },
    };
    Scene {
        name: "moving".into(),
        meshes: vec![floor.finish("floor", 0), wall.finish("wall", 0), ball, door],
        materials: vec![
            Material::plain("white", Vec3::splat(0.8)),
            Material::plain("ball", Vec3::new(0.8, 0.3, 0.2)),
            Material::plain("door", Vec3::new(0.5, 0.35, 0.2)),
        ],
        lights: vec![Light::default_sun()],
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(eye_at(DVec3::new(0.4, 1.5, 2.2), DVec3::new(0.4, 0.3, WALL_Z))),
        nodes: vec![ball_node, door_node],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ball_rolls_on_the_floor_and_the_door_swings_on_its_hinge() {
        let scene = moving();
        assert!(scene.is_animated() && !scene.has_alpha_test());
        assert_eq!(scene.animation_period(), MOVING_PERIOD);
        for k in 0..=16 {
            let t = k as f64 * 0.25;
            let frozen = scene.at_time(t);
            let ball = frozen.meshes.iter().find(|m| m.name == "ball").unwrap();
            let lowest = ball.positions.iter().map(|p| ball.origin.y + p.y as f64).fold(f64::INFINITY, f64::min);
            assert!(lowest.abs() < 2e-3, "t = {t}: the ball's lowest point is at y = {lowest}");
            let door = frozen.meshes.iter().find(|m| m.name == "door").unwrap();
            let behind = door.positions.iter().map(|p| door.origin.z + p.z as f64).fold(f64::INFINITY, f64::min);
            assert!(behind >= WALL_Z - 1e-6, "t = {t}: the door passes through the wall ({behind})");
        }
        // Half way the ball is at the far end and the door fully open.
        let door_now = scene.node_transforms(2.0)[1];
        let edge = door_now.transform_point3(DVec3::new(0.0, 0.0, 0.9));
        assert!((edge.x - (DOOR_HINGE_X - 0.9 * DOOR_SWING_DEG.to_radians().sin())).abs() < 1e-9, "{edge}");
        // The open door stays clear of the ball at the end of its path.
        assert!(edge.x > BALL_TRAVEL + BALL_RADIUS + 0.3, "{edge}");
        assert!((scene.node_transforms(2.0)[0].w_axis.x - BALL_TRAVEL).abs() < 1e-9);
    }

    #[test]
    fn the_grille_is_a_checker_of_holes() {
        let scene = grille();
        assert!(scene.has_alpha_test() && !scene.is_animated());
        assert_eq!(grille_solid_at(-0.99, -0.99), Some(true));
        assert_eq!(grille_solid_at(-0.99 + 0.25, -0.99), Some(false));
        assert_eq!(grille_solid_at(1.5, 0.0), None);
    }
}
