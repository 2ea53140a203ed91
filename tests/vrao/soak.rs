//! The soak run: the simulated headset for 5,000 frames at a small size, with the
//! compositor warping every late frame. Memory (RSS) and the number of live GPU
//! resources must stay flat after warm-up. It runs in a process of its own (the other
//! tests of the binary would move its memory).

use crate::common;

use vrao::app::FrameLoop;
use vrao::xr::simulated::motion::HeadMotion;
use vrao::xr::simulated::reproject::ReprojectionMode;
use vrao::xr::simulated::{SimulatedHeadset, SimulatedOptions, TimeMode};
use vrao_ao::AoSettings;
use vrao_render::{HeadsetProfile, Scene, Settings};

/// Resident set size of this process in KiB (Linux /proc).
fn rss_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmRSS:")).unwrap();
    line.split_whitespace().nth(1).unwrap().parse().unwrap()
}

/// Live (kept by the user) wgpu objects of each kind.
fn live_gpu_objects(instance: &wgpu::Instance) -> Vec<(&'static str, usize)> {
    let Some(report) = instance.generate_report() else { return Vec::new() };
    let hub = report.hub_report();
    let live = |r: &wgpu::wgc::registry::RegistryReport| r.num_kept_from_user;
    vec![
        ("buffers", live(&hub.buffers)),
        ("textures", live(&hub.textures)),
        ("texture views", live(&hub.texture_views)),
        ("bind groups", live(&hub.bind_groups)),
        ("samplers", live(&hub.samplers)),
        ("compute pipelines", live(&hub.compute_pipelines)),
        ("render pipelines", live(&hub.render_pipelines)),
        ("query sets", live(&hub.query_sets)),
        ("command buffers", live(&hub.command_buffers)),
    ]
}

#[test]
fn five_thousand_frames_keep_memory_and_gpu_resources_flat() {
    const FRAMES: u64 = 5000;
    const WARMUP: u64 = 200;
    if !common::alone_in_a_process() {
        return;
    }
    let (gpu, _lock) = common::gpu();
    let scene = Scene::load("builtin:room").unwrap();
    let settings = Settings {
        profile: HeadsetProfile::with_size("soak", 32, 32),
        // The bilateral blur is off: on lavapipe 22.3 its two dispatches grow RSS by about
        // 0.5 MB a frame inside the driver (wgpu's live objects stay flat; reported in
        // the closing note of the numerics issue). Everything else runs.
        ao: AoSettings { resolution: vrao_ao::Resolution::Half, blur_radius: 0, ..AoSettings::default() },
        ..Settings::default()
    };
    let headset = SimulatedHeadset::new(SimulatedOptions {
        profile: settings.profile,
        near: settings.near,
        path: scene.head.clone(),
        motion: HeadMotion::FigureEight,
        // Some frames late, so the compositor warps (depth-based) as well as presents.
        time: TimeMode::Virtual { render_ms: vec![5.0, 9.0, 14.0, 30.0] },
        reprojection: ReprojectionMode::Depth,
        compose: true,
        frames: Some(FRAMES),
    })
    .unwrap();
    let mut frame_loop = FrameLoop::new(gpu.clone(), &scene, &settings, Box::new(headset)).unwrap();
    let (mut rss_start, mut objects_start) = (0, Vec::new());
    while let Some(step) = frame_loop.step().unwrap() {
        if step.request.index + 1 == WARMUP {
            gpu.wait_idle().unwrap();
            rss_start = rss_kib();
            objects_start = live_gpu_objects(gpu.instance.as_ref().expect("Gpu::new opens an instance"));
        }
    }
    frame_loop.end().unwrap();
    gpu.wait_idle().unwrap();
    let rss_end = rss_kib();
    let objects_end = live_gpu_objects(gpu.instance.as_ref().expect("Gpu::new opens an instance"));
    let counters = frame_loop.headset.counters();
    eprintln!(
        "soak: {FRAMES} frames; RSS after {WARMUP} frames {rss_start} KiB, at the end {rss_end} KiB; counters {counters:?}; live GPU objects {objects_end:?}"
    );
    assert_eq!(frame_loop.frames, FRAMES);
    assert!(counters.presented > 0 && counters.reprojected > 0, "{counters:?}");
    assert_eq!(objects_start, objects_end, "live GPU objects grew");
    // Allocator noise only: 4,800 frames leaking even 1 KiB each would add 4.8 MiB.
    assert!(rss_end < rss_start + 4096, "RSS grew from {rss_start} KiB to {rss_end} KiB");
}
