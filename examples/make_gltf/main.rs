//! Writes vrao's glTF test assets into a folder:
//!
//! - `grille.glb`: a checker-masked grille (alpha MASK, cutoff 0.5) 0.5 m over a floor,
//!   a sun and a camera looking down at it;
//! - `grille.obj` + `grille.mtl` + `grille_mask.png`: the same grille as OBJ, its holes
//!   from `map_d`;
//! - `sibenik.glb`: `$VRAO_SCENES/sibenik/sibenik.obj` converted (skipped without it);
//! - `terrain.glb` and `terrain.obj`: the same 1,002,528-triangle height field;
//! - the fidelity assets (`fidelity.rs`): `tiles.glb` (repeat, mirrored repeat, clamp),
//!   `emissive.glb`, `vertex_colors.glb`, `normal_map.glb` and `normal_map_flat.glb`,
//!   `modes.gltf` (strip, fan, list, lines, points), `quantized.gltf`, `sparse.gltf`.
//!
//! An example rather than a `vrao` subcommand: it is a generator for developers and tests,
//! not something a user of the renderer needs, and it runs without the application
//! features. Run: `cargo run --release --example make_gltf -- OUT_DIR`. The files are
//! large (the terrain 81 MB as OBJ, 24 MB as .glb); keep them out of the repository.
//! `make_gltf load FILE` loads a scene and prints its load time and peak memory.

mod fidelity;

use glam::{DVec3, Vec2, Vec3};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vrao::test_assets::gltf_write::{write, WriteOptions};
use vrao_ao::HeadPose;
use vrao_render::scene::{AlphaMode, HeadPath, Light, Material, Mesh, Scene, Texture};

/// Cells per side of the grille's checker.
const CHECKER: u32 = 8;
/// Quads per side of the terrain: 2 × 708² = 1,002,528 triangles.
const TERRAIN_QUADS: usize = 708;

fn main() {
    // `make_gltf load FILE`: loads one scene and prints its load time and the process's
    // peak memory (VmHWM), for the README's OBJ-against-glTF table (one process per file,
    // so the peaks do not mix).
    if std::env::args().nth(1).as_deref() == Some("load") {
        let file = std::env::args().nth(2).unwrap_or_default();
        let started = std::time::Instant::now();
        match Scene::load(&file) {
            Ok(scene) => {
                let seconds = started.elapsed().as_secs_f64();
                let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
                let peak = status.lines().find(|l| l.starts_with("VmHWM")).unwrap_or("VmHWM: ?").to_string();
                println!("{file}: {} triangles in {seconds:.2} s; {peak}", scene.triangle_count());
            }
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        }
        return;
    }
    let Some(out) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: make_gltf OUT_DIR | make_gltf load FILE");
        std::process::exit(2);
    };
    if let Err(e) = run(&out) {
        eprintln!("{e}");
        std::process::exit(2);
    }
}

fn run(out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(out)?;
    let grille = grille_scene();
    let camera = grille.head.pose_at(0.0);
    write(&grille, &out.join("grille.glb"), &WriteOptions { camera: Some(camera), ..WriteOptions::default() })?;
    write_grille_obj(out)?;
    println!("wrote grille.glb, grille.obj, grille.mtl, grille_mask.png");
    fidelity::write_all(out)?;

    match vrao_render::scene::shared_scenes_dir().map(|d| d.join("sibenik/sibenik.obj")).filter(|p| p.is_file()) {
        Some(obj) => {
            let scene = Scene::load(obj.to_str().ok_or("non-UTF-8 path")?)?;
            write(&scene, &out.join("sibenik.glb"), &WriteOptions::default())?;
            println!("wrote sibenik.glb ({} triangles)", scene.triangle_count());
        }
        None => println!("skipped sibenik.glb: $VRAO_SCENES/sibenik/sibenik.obj not found"),
    }

    let (positions, normals, indices) = terrain();
    write_obj(&out.join("terrain.obj"), &positions, &normals, &indices)?;
    let world: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let (origin, offsets) = Mesh::recentre(&world);
    let mesh = Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: "terrain".into(),
        origin,
        positions: offsets,
        normals,
        uvs: vec![Vec2::ZERO; positions.len()],
        uvs1: Vec::new(),
        indices,
        material: 0,
        node: None,
    };
    let scene = plain_scene("terrain", vec![mesh], vec![Material::plain("ground", Vec3::splat(0.6))]);
    write(&scene, &out.join("terrain.glb"), &WriteOptions::default())?;
    println!("wrote terrain.glb and terrain.obj ({} triangles)", scene.triangle_count());
    Ok(())
}

fn plain_scene(name: &str, meshes: Vec<Mesh>, materials: Vec<Material>) -> Scene {
    Scene {
        name: name.into(),
        meshes,
        materials,
        lights: vec![Light::default_sun()],
        environment: None,
        head: HeadPath::fixed(HeadPose::IDENTITY),
        nodes: Vec::new(),
    }
}

/// A horizontal quad at height `y`, `size` on a side, facing up, uv over [0, 1]².
fn quad(name: &str, y: f64, size: f32, material: usize) -> Mesh {
    let h = size / 2.0;
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: name.into(),
        origin: DVec3::new(0.0, y, 0.0),
        positions: vec![Vec3::new(-h, 0.0, h), Vec3::new(h, 0.0, h), Vec3::new(h, 0.0, -h), Vec3::new(-h, 0.0, -h)],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO],
        uvs1: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        node: None,
    }
}

/// The checker's coverage: solid cells 255, holes 0.
fn checker_alpha(x: u32, y: u32) -> u8 {
    if (x + y).is_multiple_of(2) {
        255
    } else {
        0
    }
}

fn grille_scene() -> Scene {
    let rgba8 = (0..CHECKER * CHECKER)
        .flat_map(|i| {
            let (x, y) = (i % CHECKER, i / CHECKER);
            [230, 230, 230, checker_alpha(x, y)]
        })
        .collect::<Vec<u8>>()
        .into();
    let mut grille = Material::plain("grille", Vec3::new(0.7, 0.6, 0.5));
    grille.diffuse_texture =
        Some(Texture { sampling: Default::default(), width: CHECKER, height: CHECKER, rgba8, source: None });
    grille.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let materials = vec![Material::plain("floor", Vec3::splat(0.7)), grille];
    let meshes = vec![quad("floor", 0.0, 4.0, 0), quad("grille", 0.5, 2.0, 1)];
    let mut scene = plain_scene("grille", meshes, materials);
    scene.lights = vec![Light::Directional {
        direction: Vec3::new(0.2, -1.0, -0.3).normalize(),
        color: Vec3::ONE,
        intensity: 3.0,
    }];
    let pose = HeadPose::look_at(DVec3::new(0.0, 2.2, 2.4), DVec3::new(0.0, 0.0, 0.0)).unwrap_or(HeadPose::IDENTITY);
    scene.head = HeadPath::fixed(pose);
    scene
}

/// The grille as OBJ + MTL: the floor grey, the grille white-textured with its holes in
/// `map_d` (a greyscale PNG).
fn write_grille_obj(out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let mask = image::GrayImage::from_fn(CHECKER, CHECKER, |x, y| image::Luma([checker_alpha(x, y)]));
    mask.save(out.join("grille_mask.png"))?;
    std::fs::write(
        out.join("grille.mtl"),
        "newmtl floor\nKd 0.7 0.7 0.7\n\nnewmtl grille\nKd 0.7 0.6 0.5\nmap_d grille_mask.png\n",
    )?;
    let mut obj = String::from("mtllib grille.mtl\n");
    for (y, h) in [(0.0, 2.0), (0.5, 1.0)] {
        for (x, z) in [(-h, h), (h, h), (h, -h), (-h, -h)] {
            writeln!(obj, "v {x} {y} {z}")?;
        }
    }
    // OBJ's v runs bottom-up; vrao flips it, so these match the .glb's texels.
    obj.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n");
    obj.push_str("o floor\nusemtl floor\nf 1/1/1 2/2/1 3/3/1 4/4/1\n");
    obj.push_str("o grille\nusemtl grille\nf 5/1/1 6/2/1 7/3/1 8/4/1\n");
    std::fs::write(out.join("grille.obj"), obj)?;
    Ok(())
}

/// A rolling height field, 20 m across: world positions, normals, indices.
fn terrain() -> (Vec<Vec3>, Vec<Vec3>, Vec<u32>) {
    let n = TERRAIN_QUADS + 1;
    let height = |x: f32, z: f32| 0.6 * (0.7 * x).sin() * (0.5 * z).cos() + 0.15 * (2.3 * x + 1.7 * z).sin();
    let mut positions = Vec::with_capacity(n * n);
    let mut normals = Vec::with_capacity(n * n);
    let step = 20.0 / TERRAIN_QUADS as f32;
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (-10.0 + i as f32 * step, -10.0 + j as f32 * step);
            positions.push(Vec3::new(x, height(x, z), z));
            let e = 1e-3;
            let dx = (height(x + e, z) - height(x - e, z)) / (2.0 * e);
            let dz = (height(x, z + e) - height(x, z - e)) / (2.0 * e);
            normals.push(Vec3::new(-dx, 1.0, -dz).normalize());
        }
    }
    let mut indices = Vec::with_capacity(6 * TERRAIN_QUADS * TERRAIN_QUADS);
    for j in 0..TERRAIN_QUADS {
        for i in 0..TERRAIN_QUADS {
            let a = (j * n + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
            // Counter-clockwise seen from above (+Y).
            indices.extend([a, c, b, b, c, d]);
        }
    }
    (positions, normals, indices)
}

fn write_obj(path: &Path, positions: &[Vec3], normals: &[Vec3], indices: &[u32]) -> std::io::Result<()> {
    let mut text = String::with_capacity(positions.len() * 64 + indices.len() * 8);
    text.push_str("o terrain\n");
    for p in positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in normals {
        let _ = writeln!(text, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    std::fs::write(path, text)
}
