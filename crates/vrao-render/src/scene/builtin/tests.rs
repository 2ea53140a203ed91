//! Tests of `builtin.rs`.

use super::*;

#[test]
fn every_builtin_has_unit_normals_that_agree_with_winding() {
    // "flipped-normals" breaks the agreement on purpose (its normals lie, see
    // `flipped_normals_point_into_the_ball_only_where_meant`); its normals are unit.
    for name in names().iter().filter(|n| **n != "flipped-normals") {
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

/// Every triangle of `scene` in world space, with its unit face normal (from the winding).
fn world_triangles(scene: &Scene) -> Vec<([DVec3; 3], DVec3)> {
    let mut out = Vec::new();
    for m in &scene.meshes {
        for t in m.indices.chunks(3) {
            let v = [t[0], t[1], t[2]].map(|i| m.origin + m.positions[i as usize].as_dvec3());
            out.push((v, (v[1] - v[0]).cross(v[2] - v[0]).normalize()));
        }
    }
    out
}

/// The nearest triangle that the ray `origin + t·dir` (t > 0) hits: (t, face normal).
fn cast(triangles: &[([DVec3; 3], DVec3)], origin: DVec3, dir: DVec3) -> Option<(f64, DVec3)> {
    let mut best: Option<(f64, DVec3)> = None;
    for ([a, b, c], normal) in triangles {
        // Möller–Trumbore.
        let (e1, e2) = (*b - *a, *c - *a);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = origin - *a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 1e-9 && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, *normal));
        }
    }
    best
}

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
fn directions(n: usize) -> impl Iterator<Item = DVec3> {
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |i| {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).sqrt();
        let phi = golden * i as f64;
        DVec3::new(r * phi.cos(), y, r * phi.sin())
    })
}

/// The head's centre and both eyes (at the default 64 mm apart).
fn eyes(scene: &Scene) -> [DVec3; 3] {
    let head = scene.head.keys[0].1;
    let right = head.orientation * DVec3::X * 0.032;
    [head.position, head.position - right, head.position + right]
}

/// Every mesh of `scene` named in `names` is closed and consistently wound: welded by
/// position, each directed edge a→b is matched by as many b→a (a union of closed
/// surfaces, each counter-clockwise seen from outside).
fn assert_closed(scene: &Scene, names: &[&str]) {
    use std::collections::HashMap;
    for name in names {
        let m = scene.meshes.iter().find(|m| m.name == *name).unwrap_or_else(|| panic!("no mesh {name}"));
        let key = |i: u32| (m.origin + m.positions[i as usize].as_dvec3()).to_array().map(|c| (c * 1e5).round() as i64);
        let mut edges: HashMap<_, i32> = HashMap::new();
        for t in m.indices.chunks(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (ka, kb) = (key(a), key(b));
                if ka < kb {
                    *edges.entry((ka, kb)).or_default() += 1;
                } else {
                    *edges.entry((kb, ka)).or_default() -= 1;
                }
            }
        }
        let open = edges.values().filter(|&&count| count != 0).count();
        assert_eq!(open, 0, "{}/{name}: {open} edges without a matching opposite edge", scene.name);
    }
}

#[test]
fn new_scenes_stay_modest() {
    for name in ["furnished", "columns", "flipped-normals"] {
        let count = load(name).unwrap().triangle_count();
        assert!((100..50_000).contains(&count), "{name}: {count} triangles");
    }
}

#[test]
fn furnished_room_is_closed_faces_inward_and_holds_the_eyes() {
    use super::super::furnished::*;
    let scene = load("furnished").unwrap();
    assert_eq!(scene.environment.as_ref().map(|e| e.intensity), Some(FURNISHED_AMBIENT));
    let bounds = scene.bounds();
    let expected_min = FURNISHED_MIN - DVec3::Z * FURNISHED_RECESS_DEPTH;
    assert!(bounds.min.abs_diff_eq(expected_min, 1e-6) && bounds.max.abs_diff_eq(FURNISHED_MAX, 1e-6), "{bounds:?}");
    let triangles = world_triangles(&scene);
    // From both eyes and the light, every direction meets a face from its front: the
    // shell has no gap, faces in, and none of them is inside furniture.
    let Light::Point { position: light, .. } = scene.lights[0] else { panic!("a point light") };
    for origin in eyes(&scene).into_iter().chain([light]) {
        let inside = origin.cmpgt(FURNISHED_MIN).all() && origin.cmplt(FURNISHED_MAX).all();
        assert!(inside, "{origin} is outside the room");
        for dir in directions(2000) {
            let (t, normal) = cast(&triangles, origin, dir).unwrap_or_else(|| panic!("{origin}: ray {dir} escapes"));
            assert!(normal.dot(dir) < 0.0, "{origin}: ray {dir} meets a back face at {t:.3} m");
        }
    }
    assert!((FURNISHED_EYE.y - 1.6).abs() < 1e-12, "standing height");
    let furniture = ["skirting", "table", "chairs", "shelves", "books 0", "books 1", "books 2", "blind"];
    assert_closed(&scene, &furniture);
}

#[test]
fn furnished_room_has_its_thin_parts_in_view() {
    use super::super::furnished::*;
    let scene = load("furnished").unwrap();
    let mesh = |name: &str| scene.meshes.iter().find(|m| m.name == name).unwrap();
    let mesh_bounds = |name: &str| {
        let m = mesh(name);
        let mut b = crate::scene::Aabb::EMPTY;
        m.positions.iter().for_each(|p| b.extend(m.origin + p.as_dvec3()));
        b
    };
    let table = mesh_bounds("table");
    assert!(table.min.y.abs() < 1e-6 && (table.max.y - TABLE_MAX.y).abs() < 1e-6, "{table:?}");
    assert_eq!(mesh("table").indices.len() / 3, 5 * 12, "a top and four legs");
    assert!(mesh_bounds("chairs").min.y.abs() < 1e-6, "chairs stand on the floor");
    // Slats: boxes of 12 triangles (36 indices); the head rail, bottom rail and two cords are 4 more.
    let slats = mesh("blind").indices.len() / 36 - 4;
    let [y0, y1] = [FURNISHED_WINDOW_MIN[1], FURNISHED_WINDOW_MAX[1]];
    assert_eq!(slats, ((y1 - y0) / SLAT_PITCH).ceil() as usize, "slats cover the window");
    // The table, the blind and three of the room's corners lie in front of the head,
    // within 50° of where it looks, and nothing hides them; so do chair legs.
    let head = scene.head.keys[0].1;
    let forward = head.orientation * DVec3::NEG_Z;
    let triangles = world_triangles(&scene);
    let blind = mesh_bounds("blind").center();
    let (lo, hi) = (FURNISHED_MIN, FURNISHED_MAX);
    let table_top = (TABLE_MIN + TABLE_MAX) * 0.5 + DVec3::Y * 0.02;
    for (what, target) in [
        ("table", table_top),
        ("blind", blind),
        ("left wall–floor corner", DVec3::new(lo.x + 0.005, 0.1, -3.0)),
        ("back-left corner", DVec3::new(lo.x + 0.005, 1.2, lo.z + 0.005)),
        ("back wall–ceiling corner", DVec3::new(0.0, hi.y - 0.005, lo.z + 0.005)),
    ] {
        let to = target - head.position;
        assert!(to.normalize().dot(forward) > 50f64.to_radians().cos(), "{what} is out of view");
        let (t, _) = cast(&triangles, head.position, to.normalize()).unwrap();
        assert!(t > to.length() - 0.05, "{what} is hidden at {t:.2} of {:.2} m", to.length());
    }
    let legs_in_view = mesh("chairs").positions.iter().any(|p| {
        let world = mesh("chairs").origin + p.as_dvec3();
        let to = world - head.position;
        world.y < 0.3 && to.normalize().dot(forward) > 40f64.to_radians().cos()
    });
    assert!(legs_in_view, "a chair leg is in view");
}

#[test]
fn columns_stand_on_the_floor_beside_far_depth() {
    use super::super::edge_cases::*;
    let scene = load("columns").unwrap();
    assert_closed(&scene, &["round columns", "square column", "pole", "wall", "slab", "boxes", "bench", "ball"]);
    for m in scene.meshes.iter().filter(|m| m.name != "floor") {
        let lowest = m.positions.iter().map(|p| m.origin.y + p.y as f64).fold(f64::INFINITY, f64::min);
        if m.name == "slab" {
            assert!((lowest - SLAB_MIN.y).abs() < 1e-6, "the slab floats");
        } else {
            assert!(lowest.abs() < 1e-6, "{} stands on the floor ({lowest})", m.name);
        }
    }
    let pole = scene.meshes.iter().find(|m| m.name == "pole").unwrap();
    let width = pole.positions.iter().map(|p| p.x).fold(f32::MIN, f32::max)
        - pole.positions.iter().map(|p| p.x).fold(f32::MAX, f32::min);
    assert!((width as f64 - 2.0 * POLE_RADIUS).abs() < 1e-4, "pole {width} m wide");
    // Just beside each round column's silhouette at 1 m height, the eye sees something
    // at least 1.5 m further away: a depth edge against far floor or wall.
    let triangles = world_triangles(&scene);
    for [x, z] in COLUMN_SITES {
        let centre = DVec3::new(x, 1.0, z);
        let to = centre - COLUMNS_EYE;
        let side = to.cross(DVec3::Y).normalize();
        let (t_hit, _) = cast(&triangles, COLUMNS_EYE, to.normalize()).unwrap();
        assert!(t_hit < to.length(), "column at {x}, {z} in view");
        let beside = centre + side * (COLUMN_RADIUS * 1.05) - COLUMNS_EYE;
        let t_beside = cast(&triangles, COLUMNS_EYE, beside.normalize()).map_or(f64::INFINITY, |h| h.0);
        assert!(t_beside > to.length() + 1.5, "column at {x}, {z}: {t_beside:.2} m beside it");
    }
}

#[test]
fn flipped_normals_point_into_the_ball_only_where_meant() {
    use super::super::edge_cases::*;
    let scene = load("flipped-normals").unwrap();
    let [floor, ball] = [&scene.meshes[0], &scene.meshes[1]];
    assert!(floor.normals.iter().all(|n| *n == Vec3::Y));
    let (mut inward, mut silhouette_turned) = (0, [0, 0]);
    for (p, n) in ball.positions.iter().zip(&ball.normals) {
        assert!((n.length() - 1.0).abs() < 1e-5, "normals stay unit");
        let world = ball.origin + p.as_dvec3();
        let outward = (world - SPHERE_CENTER).normalize();
        let agreement = n.as_dvec3().dot(outward);
        if agreement < 0.0 {
            inward += 1;
        }
        let facing = outward.dot((FLIPPED_EYE - world).normalize());
        if facing.abs() < SILHOUETTE_COS && world.y > SPHERE_CENTER.y {
            assert!((agreement + 0.5).abs() < 1e-5, "silhouette normals are turned 120°");
            silhouette_turned[(world.x < 0.0) as usize] += 1;
        } else {
            assert!(agreement.abs() > 0.999, "elsewhere normals are radial or flipped");
        }
    }
    let scattered = inward - silhouette_turned.iter().sum::<usize>();
    assert!((10..=100).contains(&scattered), "{scattered} scattered flipped normals of {}", ball.normals.len());
    assert!(silhouette_turned.iter().all(|&n| n >= 10), "{silhouette_turned:?}");
    // The geometry itself is right: every triangle is wound counter-clockwise seen from
    // outside the ball.
    for ([a, b, c], face) in world_triangles(&scene).into_iter().skip(floor.indices.len() / 3) {
        assert!(face.dot(((a + b + c) / 3.0 - SPHERE_CENTER).normalize()) > 0.95);
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
