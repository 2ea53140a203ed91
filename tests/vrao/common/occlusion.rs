//! Shared by the occlusion tests (tests/occlusion_*.rs): the techniques, settings for a
//! frame, one rendered stereo frame with its outputs read back and every pixel's world
//! position, and the same-surface blur that models the bilateral blur on an expectation
//! image.

use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;
use vrao_ao::plug::{Gpu, Resource, DEPTH};
use vrao_ao::{AoSettings, EyePair, HeadPose, Technique};
use vrao_render::scene::Scene;
use vrao_render::{FrameReport, HeadsetProfile, Renderer, Settings};

/// The techniques that compute occlusion.
pub(crate) fn ao_techniques() -> Vec<Technique> {
    Technique::estimators()
}

/// Their pass names, as the plan and `--explain` name them.
pub(crate) fn ao_passes() -> Vec<&'static str> {
    Technique::estimators().iter().map(|t| t.name()).collect()
}

pub(crate) fn settings(width: u32, height: u32, ao: AoSettings) -> Settings {
    Settings { profile: HeadsetProfile::with_size("test", width, height), ao, ..Settings::default() }
}

pub(crate) fn ao(technique: Technique, samples: u32, radius: f32) -> AoSettings {
    AoSettings { technique, samples, radius, ..AoSettings::default() }
}

/// One rendered stereo frame: the eyes, the depth, every pixel's world position and the
/// requested outputs read back (one Vec per eye layer, RGBA interleaved).
pub(crate) struct Frame {
    pub width: u32,
    pub height: u32,
    pub eyes: EyePair,
    /// World position per layer and pixel; `None` on the sky.
    pub world: Vec<Vec<Option<DVec3>>>,
    pub outputs: BTreeMap<Resource, Vec<Vec<f32>>>,
    pub report: FrameReport,
}

pub(crate) fn render(gpu: &Arc<Gpu>, scene: &Scene, s: &Settings, head: &HeadPose, outputs: &[Resource]) -> Frame {
    let mut renderer = Renderer::new(gpu.clone(), scene, s).unwrap();
    let eyes = s.profile.eyes(head, s.near);
    let mut wanted = outputs.to_vec();
    wanted.push(DEPTH);
    let report = renderer.render(&eyes.eyes, &wanted).unwrap();
    let depth = renderer.read_f32(DEPTH).unwrap();
    let (w, h) = (s.profile.width, s.profile.height);
    let world = super::world_positions(&depth, &eyes.eyes, w, h, s.near);
    let outputs = outputs.iter().map(|&r| (r, renderer.read_f32(r).unwrap())).collect();
    Frame { width: w, height: h, eyes, world, outputs, report }
}

impl Frame {
    pub(crate) fn index(&self, x: u32, y: u32) -> usize {
        (y * self.width + x) as usize
    }
    pub(crate) fn world(&self, layer: usize, x: u32, y: u32) -> Option<DVec3> {
        self.world[layer][self.index(x, y)]
    }
    /// Alpha (AO) of a full-resolution output at a pixel.
    pub(crate) fn ao(&self, r: Resource, layer: usize, x: u32, y: u32) -> f64 {
        self.outputs[&r][layer][4 * self.index(x, y) + 3] as f64
    }
    pub(crate) fn rgb(&self, r: Resource, layer: usize, x: u32, y: u32) -> [f32; 3] {
        let i = 4 * self.index(x, y);
        let v = &self.outputs[&r][layer];
        [v[i], v[i + 1], v[i + 2]]
    }
    pub(crate) fn pixels(&self) -> impl Iterator<Item = (usize, u32, u32)> + '_ {
        let (w, h) = (self.width, self.height);
        (0..2usize).flat_map(move |l| (0..h).flat_map(move |y| (0..w).map(move |x| (l, x, y))))
    }
    /// Where a world point lands in `layer`, as a pixel, if on screen.
    pub(crate) fn pixel_of(&self, layer: usize, p: DVec3) -> Option<(u32, u32)> {
        let (uv, _) = self.eyes.eyes[layer].project(p, self.eyes.near)?;
        let (x, y) = (uv[0] * self.width as f64, uv[1] * self.height as f64);
        (x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64).then_some((x as u32, y as u32))
    }
    /// Whether a world point projects inside `layer` with `margin` (in uv) to spare.
    pub(crate) fn on_screen(&self, layer: usize, p: DVec3, margin: f64) -> bool {
        self.eyes.eyes[layer]
            .project(p, self.eyes.near)
            .is_some_and(|(uv, _)| uv.iter().all(|&c| c >= margin && c <= 1.0 - margin))
    }
    pub(crate) fn forward(&self, layer: usize) -> DVec3 {
        self.eyes.eyes[layer].pose.orientation * DVec3::NEG_Z
    }
}

pub(crate) fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in values {
        sum += v;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// The blur's effect on a field that is smooth within each surface: a normalised
/// separable Gaussian (σ = radius / 2, taps within ±radius, off-image taps skipped) that
/// only averages pixels of the same surface class. On a plane the renderer's bilateral
/// weights (src/render/passes/blur/bilateral.wgsl: tangent-plane distance and normal agreement) are 1
/// between same-plane pixels and vanish across a crease or a depth step, so this is what
/// the blur does to an expectation image. Class 0 pixels are neither changed nor used.
pub(crate) fn same_surface_blur(values: &[f64], class: &[u8], width: u32, height: u32, radius: i32) -> Vec<f64> {
    let sigma = (radius as f64 * 0.5).max(0.5);
    let (w, h) = (width as i32, height as i32);
    let pass = |input: &[f64], axis: (i32, i32)| -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if class[i as usize] == 0 {
                    return input[i as usize];
                }
                let (mut sum, mut total) = (0.0, 0.0);
                for k in -radius..=radius {
                    let (qx, qy) = (x + axis.0 * k, y + axis.1 * k);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let q = (qy * w + qx) as usize;
                    if class[q] == class[i as usize] {
                        let weight = (-(k * k) as f64 / (2.0 * sigma * sigma)).exp();
                        sum += weight * input[q];
                        total += weight;
                    }
                }
                sum / total
            })
            .collect()
    };
    pass(&pass(values, (1, 0)), (0, 1))
}
