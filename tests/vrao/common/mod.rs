//! Shared by the integration tests: one device for the test binary, one GPU test at a time
//! (lavapipe uses every core; parallel frames only slow each other down), and the public
//! scenes, whose absence a test reports as a skip rather than a silent pass.

#![allow(dead_code)]

// The occlusion tests' frame and crease helpers (tests/occlusion_*.rs, all of which
// require `app`; the crease needs `vrao::measure`).
#[cfg(feature = "app")]
pub(crate) mod crease;
#[cfg(feature = "app")]
pub(crate) mod occlusion;

use std::io::Write;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use vrao_ao::plug::Gpu;
use vrao_render::scene::{HeadPath, Material, Mesh, Scene};
use vrao_render::BackendChoice;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Holds the GPU for one test (also for tests that run the `vrao` binary).
pub(crate) fn gpu_lock() -> MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The public scene file `relative` (under `$VRAO_SCENES`, or `shared/scenes` beside the
/// repository), or `None` after reporting the calling test as skipped.
pub(crate) fn public_scene(relative: &str) -> Option<PathBuf> {
    let path = public_scenes()?.join(relative);
    if path.is_file() {
        return Some(path);
    }
    skip(&format!("needs the public scene {relative}"));
    None
}

/// The public scenes' directory, or `None` after reporting the calling test as skipped.
pub(crate) fn public_scenes() -> Option<PathBuf> {
    let dir = vrao_render::scene::shared_scenes_dir();
    if dir.is_none() {
        skip("needs the public scenes (shared/scenes beside the repository, or $VRAO_SCENES)");
    }
    dir
}

/// Reports the calling test as skipped: a line on stderr and, when `VRAO_SKIP_LOG` names a
/// file (`.ci/test` sets it and prints the count and reasons after the run), a line there.
/// Under CI (`CI` set) a skip is a failure: CI must run every test.
pub(crate) fn skip(reason: &str) {
    let test = std::thread::current().name().unwrap_or("(unnamed test)").to_string();
    assert!(std::env::var_os("CI").is_none(), "{test} cannot run under CI: it {reason}");
    eprintln!("skipped {test}: it {reason}");
    if let Some(log) = std::env::var_os("VRAO_SKIP_LOG") {
        let line = format!("{test}: {reason}\n");
        let appended = std::fs::OpenOptions::new().create(true).append(true).open(&log);
        appended.and_then(|mut file| file.write_all(line.as_bytes())).expect("VRAO_SKIP_LOG is writable");
    }
}

/// For a test that measures its whole process (its memory): true in a child process of
/// this test binary that runs the calling test alone; in the test binary itself, runs that
/// child (holding the GPU), fails if it fails, and returns false.
pub(crate) fn alone_in_a_process() -> bool {
    const CHILD: &str = "VRAO_TEST_ALONE";
    if std::env::var_os(CHILD).is_some() {
        return true;
    }
    let test = std::thread::current().name().expect("libtest names its threads").to_string();
    let _one_at_a_time = gpu_lock();
    let child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([test.as_str(), "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&child.stderr);
    eprintln!("{said}");
    assert!(child.status.success(), "{test} failed in its own process: {said}");
    assert!(String::from_utf8_lossy(&child.stdout).contains("1 passed"), "{test} did not run in its own process");
    false
}

pub(crate) use vrao_render::test_dir::TestDir;

/// A fresh, empty [`TestDir`] named `name`.
pub(crate) fn temp_dir(name: &str) -> TestDir {
    TestDir::new(name)
}

/// A GPU of the caller's own, for a test that changes a GPU for good (a cancellation
/// token, a shader directory), with the one-at-a-time lock.
pub(crate) fn own_gpu() -> (Arc<Gpu>, MutexGuard<'static, ()>) {
    let guard = gpu_lock();
    (Arc::new(new_gpu()), guard)
}

/// The shared GPU of the test binary, with the one-at-a-time lock.
pub(crate) fn gpu() -> (Arc<Gpu>, MutexGuard<'static, ()>) {
    let guard = gpu_lock();
    (shared_gpu(), guard)
}

fn shared_gpu() -> Arc<Gpu> {
    static GPU: OnceLock<Arc<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| Arc::new(new_gpu())).clone()
}

/// The shared GPU and one of the caller's own whose AO chain keeps four channels for every
/// technique (as on a device that cannot write `R16Float` storage), with the lock.
pub(crate) fn shared_and_four_channel_gpus() -> (Arc<Gpu>, Arc<Gpu>, MutexGuard<'static, ()>) {
    let guard = gpu_lock();
    let mut four = new_gpu();
    four.caps.scalar_chain = false;
    (shared_gpu(), Arc::new(four), guard)
}

fn new_gpu() -> Gpu {
    // As the CLI does: Mesa's WSI probe complains on headless machines without it.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    vrao_render::open(BackendChoice::Auto).expect("a GPU or lavapipe is needed for GPU tests")
}

/// A square of side `size` centred on `center`, facing +Z (towards a viewer on +Z).
pub(crate) fn square(name: &str, center: glam::DVec3, size: f32, material: usize) -> Mesh {
    let h = size * 0.5;
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: name.into(),
        origin: center,
        node: None,
        positions: vec![
            glam::Vec3::new(-h, -h, 0.0),
            glam::Vec3::new(h, -h, 0.0),
            glam::Vec3::new(h, h, 0.0),
            glam::Vec3::new(-h, h, 0.0),
        ],
        normals: vec![glam::Vec3::Z; 4],
        uvs: vec![glam::Vec2::ZERO; 4],
        uvs1: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
    }
}

/// A disc of `radius` centred on `center`, facing +Z, as a 64-sided fan.
pub(crate) fn disc(name: &str, center: glam::DVec3, radius: f32, material: usize) -> Mesh {
    let sides = 64;
    let mut positions = vec![glam::Vec3::ZERO];
    let mut indices = Vec::new();
    for i in 0..sides {
        let a = i as f32 / sides as f32 * std::f32::consts::TAU;
        positions.push(glam::Vec3::new(a.cos() * radius, a.sin() * radius, 0.0));
        indices.extend([0, 1 + i, 1 + (i + 1) % sides]);
    }
    let n = positions.len();
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: name.into(),
        origin: center,
        node: None,
        positions,
        normals: vec![glam::Vec3::Z; n],
        uvs: vec![glam::Vec2::ZERO; n],
        uvs1: Vec::new(),
        indices,
        material,
    }
}

/// A scene of the given meshes with one grey material, no lights and no environment,
/// viewed from the origin looking down −Z.
pub(crate) fn bare_scene(meshes: Vec<Mesh>) -> Scene {
    Scene {
        name: "test".into(),
        meshes,
        materials: vec![Material::plain("grey", glam::Vec3::splat(0.5))],
        lights: Vec::new(),
        environment: None,
        head: HeadPath::fixed(vrao_ao::HeadPose::IDENTITY),
        nodes: Vec::new(),
    }
}

/// A closed axis-aligned box of `size` (x, y, z extents) centred on `center`: six faces,
/// normals facing out (a two-manifold solid, as depth peeling assumes).
pub(crate) fn cuboid(name: &str, center: glam::DVec3, size: glam::Vec3, material: usize) -> Mesh {
    let h = size * 0.5;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = glam::Vec3::ZERO;
            n[axis] = sign;
            // Two in-plane axes ordered so (u × v) = n: counter-clockwise seen from outside.
            let (mut u, mut v) = (glam::Vec3::ZERO, glam::Vec3::ZERO);
            u[(axis + 1) % 3] = 1.0;
            v[(axis + 2) % 3] = sign;
            let base = positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push((n + u * a + v * b) * h);
                normals.push(n);
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let uvs = vec![glam::Vec2::ZERO; positions.len()];
    Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: name.into(),
        origin: center,
        positions,
        normals,
        uvs,
        uvs1: Vec::new(),
        indices,
        material,
        node: None,
    }
}

/// The world position of every pixel of a depth readback (reversed-Z, one layer per eye,
/// `width` × `height`), or None on the sky: what the GPU tests compare pixels by.
pub(crate) fn world_positions(
    depth: &[Vec<f32>],
    eyes: &[vrao_ao::Eye],
    width: u32,
    height: u32,
    near: f64,
) -> Vec<Vec<Option<glam::DVec3>>> {
    depth
        .iter()
        .zip(eyes)
        .map(|(layer, eye)| {
            let world_from_view = eye.pose.world_from_local();
            (0..width * height)
                .map(|i| {
                    let d = layer[i as usize] as f64;
                    (d > 0.0).then(|| {
                        let uv =
                            [((i % width) as f64 + 0.5) / width as f64, ((i / width) as f64 + 0.5) / height as f64];
                        world_from_view.transform_point3(vrao_ao::Fov::view_position_from_depth(uv, d, &eye.fov, near))
                    })
                })
                .collect()
        })
        .collect()
}
