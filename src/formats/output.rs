//! Writes eye images and debug views as PNG files.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use vrao_ao::plug::{Resource, AO_RAW, DEPTH, FINAL_AO, NORMALS};
use vrao_ao::Technique;
use vrao_render::passes::gbuffer::ALBEDO;
use vrao_render::passes::tonemap::COLOR;
use vrao_render::renderer::Renderer;
use vrao_render::settings::Settings;

/// File-name parts of layer 0 and layer 1, in that order.
pub const EYE_NAMES: [&str; 2] = ["left", "right"];

fn save_rgba(path: &Path, width: u32, height: u32, rgba: Vec<u8>) -> Result<()> {
    let image = image::RgbaImage::from_raw(width, height, rgba)
        .ok_or_else(|| Error::Output { path: path.into(), message: "image size mismatch".into() })?;
    image.save(path).map_err(|e| Error::Output { path: path.into(), message: e.to_string() })
}

/// Depth shown as log-distance, near = white, far = dark, sky = black; the range is the
/// image's own nearest and farthest surface so any scale is visible.
pub fn depth_to_rgba(depth: &[f32], near: f64) -> Vec<u8> {
    let distances: Vec<f64> = depth.iter().map(|&d| if d > 0.0 { (near / d as f64).ln() } else { f64::NAN }).collect();
    let (lo, hi) = distances
        .iter()
        .filter(|d| d.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| (lo.min(d), hi.max(d)));
    let span = (hi - lo).max(1e-9);
    distances
        .iter()
        .flat_map(|&d| {
            let v = if d.is_finite() { (255.0 * (1.0 - 0.85 * (d - lo) / span)) as u8 } else { 0 };
            [v, v, v, 255]
        })
        .collect()
}

/// View-space normals mapped from [-1, 1] to [0, 255].
pub fn normals_to_rgba(normals: &[f32]) -> Vec<u8> {
    normals
        .chunks_exact(4)
        .flat_map(|n| {
            let c = |v: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0).round() as u8;
            [c(n[0]), c(n[1]), c(n[2]), 255]
        })
        .collect()
}

/// The AO channel (alpha) of an occlusion target as grey.
pub fn occlusion_to_rgba(occlusion: &[f32]) -> Vec<u8> {
    occlusion
        .chunks_exact(4)
        .flat_map(|p| {
            let v = (p[3].clamp(0.0, 1.0) * 255.0).round() as u8;
            [v, v, v, 255]
        })
        .collect()
}

/// The occlusion `vrao render` writes, with the file names' labels: the final AO (the
/// graph's named output), and with `debug` also the raw AO (nothing when no technique
/// runs).
fn occlusion_written(settings: &Settings, debug: bool) -> Vec<(&'static str, Resource)> {
    let mut written = Vec::new();
    if settings.ao.technique != Technique::None {
        written.push(("ao", FINAL_AO));
        if debug {
            written.push(("ao_raw", AO_RAW));
        }
    }
    written
}

/// What `vrao render` asks of a frame: the eyes' colour, the final AO (written beside
/// the eyes) and, with `debug`, depth, normals, albedo and the raw AO.
pub fn outputs(settings: &Settings, debug: bool) -> Vec<Resource> {
    let mut outputs = vec![COLOR];
    if debug {
        outputs.extend([DEPTH, NORMALS, ALBEDO]);
    }
    outputs.extend(occlusion_written(settings, debug).into_iter().map(|(_, r)| r));
    outputs
}

/// What a command has put on disk for its output so far (the folders it created, the
/// files it wrote), so that an interrupted command can take it all away again and leave
/// nothing behind. Clones share one trail: a Ctrl-C handler holds one while the writer
/// records into another.
#[derive(Clone, Debug, Default)]
pub struct OutputTrail {
    inner: Arc<Mutex<Trail>>,
    /// The caller's cancellation token: once set, nothing more is made.
    interrupt: Option<Arc<AtomicBool>>,
}

#[derive(Debug, Default)]
struct Trail {
    /// Folders created and files written, in order.
    made: Vec<PathBuf>,
    /// Removed: nothing more may be written.
    closed: bool,
}

impl OutputTrail {
    /// A trail with nothing on it.
    pub fn new() -> OutputTrail {
        OutputTrail::default()
    }

    /// A trail that makes nothing more (`Error::Interrupted`) once `interrupt` is set.
    pub fn interrupted_by(interrupt: Arc<AtomicBool>) -> OutputTrail {
        OutputTrail::new().interruptible(interrupt)
    }

    /// This trail (its clones share what it records) with `interrupt` as its
    /// cancellation token.
    pub fn interruptible(self, interrupt: Arc<AtomicBool>) -> OutputTrail {
        OutputTrail { interrupt: Some(interrupt), ..self }
    }

    /// The trail's cancellation token, if it has one.
    pub fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        self.interrupt.clone()
    }

    /// Whether the trail's cancellation token is set.
    pub fn interrupted(&self) -> bool {
        self.interrupt.as_ref().is_some_and(|flag| flag.load(Ordering::Relaxed))
    }

    fn lock(&self) -> MutexGuard<'_, Trail> {
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The trail, locked, unless it is closed or interrupted.
    fn open(&self) -> Result<MutexGuard<'_, Trail>> {
        let trail = self.lock();
        if trail.closed || self.interrupted() {
            return Err(Error::Engine(vrao_ao::Error::Interrupted));
        }
        Ok(trail)
    }

    /// Creates the folder `dir` and its missing parents, recording each one created.
    pub fn create_dir_all(&self, dir: &Path) -> Result<()> {
        let mut trail = self.open()?;
        let mut missing = Vec::new();
        let mut next = Some(dir);
        while let Some(d) = next.filter(|d| !d.as_os_str().is_empty() && std::fs::symlink_metadata(d).is_err()) {
            missing.push(d.to_path_buf());
            next = d.parent();
        }
        for d in missing.into_iter().rev() {
            match std::fs::create_dir(&d) {
                Ok(()) => trail.made.push(d),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(e) => return Err(Error::Output { path: d, message: format!("cannot create this directory: {e}") }),
            }
        }
        Ok(())
    }

    /// Writes the file `path` with `write`, recorded before it is made and with the
    /// trail held meanwhile, so that [`OutputTrail::remove_all`] never misses a file
    /// half written. After `remove_all`, or once interrupted, nothing is written
    /// (`Error::Interrupted`).
    pub fn write_file(&self, path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let mut trail = self.open()?;
        trail.made.push(path.to_path_buf());
        write(path)
    }

    /// Removes every file written and folder created, newest first (a folder only once
    /// empty: what others put there stays), and closes the trail to further writes.
    /// Waits for a file being written to be done first.
    pub fn remove_all(&self) {
        let mut trail = self.lock();
        trail.closed = true;
        for path in std::mem::take(&mut trail.made).into_iter().rev() {
            match std::fs::symlink_metadata(&path) {
                Ok(meta) if meta.is_dir() => drop(std::fs::remove_dir(&path)),
                Ok(_) => drop(std::fs::remove_file(&path)),
                Err(_) => {}
            }
        }
    }

    /// What is on the trail, in the order it was made.
    pub fn made(&self) -> Vec<PathBuf> {
        self.lock().made.clone()
    }
}

/// Writes `left.png` and `right.png` (or `mono.png` for one view) and, when a technique
/// ran, the final AO as grey beside them (`ao_left.png`, `ao_right.png`): the picture of
/// what the technique adds. With `debug` also the depth, normals, albedo and raw AO of
/// each view, and `marched_right.png`, the right eye's pixels its march computed rather
/// than took from the left eye (`marched_over`). Returns the files written. `trail`
/// records the folder it creates and each file, so that an interrupted command can
/// remove them again.
pub fn write_images(
    renderer: &Renderer,
    out: &Path,
    views: usize,
    debug: bool,
    trail: &OutputTrail,
) -> Result<Vec<PathBuf>> {
    trail.create_dir_all(out)?;
    let settings = renderer.settings();
    let (w, h) = (settings.profile.width, settings.profile.height);
    let names: &[&str] = if views == 2 { &EYE_NAMES } else { &["mono"] };
    let mut written = Vec::new();
    let mut save_sized = |name: String, (w, h): (u32, u32), rgba: Vec<u8>| -> Result<()> {
        let path = out.join(name);
        trail.write_file(&path, |path| save_rgba(path, w, h, rgba))?;
        written.push(path);
        Ok(())
    };
    let colours = renderer.read_bytes(COLOR)?;
    // Drawn over the right eye's colour before that is handed to its file.
    let marched = match (debug, colours.get(1)) {
        (true, Some(right)) => renderer.right_eye_marched().map(|(_, marched)| {
            let scale = if settings.ao.resolution.is_half() { 2 } else { 1 };
            marched_over(right, (w, h), &marched, scale)
        }),
        _ => None,
    };
    for (name, rgba) in names.iter().zip(colours) {
        save_sized(format!("{name}.png"), (w, h), rgba)?;
    }
    // The final AO first, then (with `debug`) the raw AO before blur or upsampling.
    for (label, r) in occlusion_written(settings, debug) {
        let target = renderer.target(r).ok_or_else(|| Error::gpu(format!("{} was not rendered", r.name())))?;
        let size = (target.width, target.height);
        for (name, layer) in names.iter().zip(renderer.read_f32(r)?) {
            save_sized(format!("{label}_{name}.png"), size, occlusion_to_rgba(&layer))?;
        }
    }
    if debug {
        let near = settings.near;
        for (name, depth) in names.iter().zip(renderer.read_f32(DEPTH)?) {
            save_sized(format!("depth_{name}.png"), (w, h), depth_to_rgba(&depth, near))?;
        }
        for (name, normals) in names.iter().zip(renderer.read_f32(NORMALS)?) {
            save_sized(format!("normals_{name}.png"), (w, h), normals_to_rgba(&normals))?;
        }
        for (name, albedo) in names.iter().zip(renderer.read_bytes(ALBEDO)?) {
            save_sized(format!("albedo_{name}.png"), (w, h), albedo)?;
        }
        if let Some(rgba) = marched {
            save_sized("marched_right.png".into(), (w, h), rgba)?;
        }
    }
    Ok(written)
}

/// The right eye's image `rgba` (`size`) in grey, with the pixels its march computed
/// rather than copied from the left eye (`marched`, occlusion pixels of `scale`×`scale`
/// image pixels each) in red: where the right eye paid, to look at beside its image for
/// seams along the listed pixels.
fn marched_over(rgba: &[u8], (w, h): (u32, u32), marched: &[[u32; 2]], scale: u32) -> Vec<u8> {
    let mut out: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| {
            let grey = ((u32::from(p[0]) * 2 + u32::from(p[1]) * 5 + u32::from(p[2])) / 8 * 3 / 4) as u8;
            [grey, grey, grey, 255]
        })
        .collect();
    for &[x, y] in marched {
        for (dx, dy) in (0..scale * scale).map(|k| (k % scale, k / scale)) {
            let (px, py) = (x * scale + dx, y * scale + dy);
            if px < w && py < h {
                let i = 4 * (py as usize * w as usize + px as usize);
                out[i] = 255;
                out[i + 2] /= 2;
            }
        }
    }
    out
}

/// Checks, before any work, that a file can be written at `path` (its folder exists and
/// takes new files, and `path` is no folder), so that a long run does not fail at its
/// end. Leaves nothing behind.
pub fn check_output_file(path: &Path) -> Result<()> {
    let refuse = |message: String| Err(Error::Output { path: path.into(), message });
    if path.is_dir() {
        return refuse("is a folder, not a file".into());
    }
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    match std::fs::metadata(folder) {
        Ok(meta) if meta.is_dir() => {
            probe_folder(folder).or_else(|e| refuse(format!("cannot write in {}: {e}", folder.display())))
        }
        Ok(_) => refuse(format!("{} is not a folder", folder.display())),
        Err(e) => refuse(format!("cannot write there: {}: {e}", folder.display())),
    }
}

/// Checks, before any work, that `path` is a folder that takes new files or can be
/// created as one (its nearest existing ancestor is a writable folder). Creates nothing.
pub fn check_output_folder(path: &Path) -> Result<()> {
    let refuse = |message: String| Err(Error::Output { path: path.into(), message });
    let mut existing = path;
    loop {
        match std::fs::metadata(existing) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) if existing == path => return refuse("is a file, not a folder".into()),
            Ok(_) => return refuse(format!("cannot create this folder: {} is a file", existing.display())),
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return refuse(format!("cannot use this folder: {e}"))
            }
            Err(_) => match existing.parent() {
                Some(parent) if !parent.as_os_str().is_empty() => existing = parent,
                _ => {
                    existing = Path::new(".");
                    break;
                }
            },
        }
    }
    probe_folder(existing).or_else(|e| refuse(format!("cannot write in {}: {e}", existing.display())))
}

/// Creates and removes a file in `folder`: the one sure test that it takes new files.
fn probe_folder(folder: &Path) -> std::io::Result<()> {
    let probe = folder.join(format!(".vrao-write-probe-{}", std::process::id()));
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// Writes `value` as pretty JSON to `path`; a failure names the path.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    let json =
        serde_json::to_string_pretty(value).map_err(|e| Error::Output { path: path.into(), message: e.to_string() })?;
    std::fs::write(path, json).map_err(|e| Error::Output { path: path.into(), message: format!("cannot write: {e}") })
}

/// `x` rounded to `digits` significant digits without trailing zeros, for text and file
/// names: 0.25612497 → "0.26", 0.5 → "0.5", 12.3 → "12" (at 2 digits).
pub fn significant(x: f64, digits: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (digits - 1 - x.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `n` and `noun`, the noun in the plural unless `n` is 1: "1 frame", "0 frames",
/// "3 changes" (regular plurals only: every noun counted in vrao's text takes an s).
pub fn count(n: u64, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_take_the_plural_unless_one() {
        assert_eq!(count(1, "frame"), "1 frame");
        assert_eq!(count(0, "frame"), "0 frames");
        assert_eq!(count(3, "change"), "3 changes");
    }

    #[test]
    fn an_output_trail_removes_what_it_made_and_nothing_else() {
        let root = std::env::temp_dir().join(format!("vrao-trail-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        std::fs::write(root.join("theirs.txt"), "kept").unwrap();
        let trail = OutputTrail::new();
        let out = root.join("a/b");
        trail.create_dir_all(&out).unwrap();
        trail.create_dir_all(&out).unwrap();
        for name in ["left.png", "right.png"] {
            trail
                .write_file(&out.join(name), |p| std::fs::write(p, "x").map_err(|e| Error::gpu(e.to_string())))
                .unwrap();
        }
        assert_eq!(trail.made(), [root.join("a"), out.clone(), out.join("left.png"), out.join("right.png")]);
        // A clone (the Ctrl-C handler's) removes it all, newest first, and closes the trail.
        trail.clone().remove_all();
        assert!(!root.join("a").exists(), "the folders it created are gone");
        assert!(root.join("theirs.txt").is_file(), "what was there before stays");
        let late = trail.write_file(&root.join("late.png"), |_| panic!("nothing is written after removal"));
        assert!(matches!(late, Err(Error::Engine(vrao_ao::Error::Interrupted))));
        // A folder something else wrote into stays.
        let trail = OutputTrail::new();
        trail.create_dir_all(&root.join("c")).unwrap();
        std::fs::write(root.join("c/other.txt"), "not the trail's").unwrap();
        trail.remove_all();
        assert!(root.join("c/other.txt").is_file());
        // Interrupted: nothing is made at all.
        let flag = Arc::new(AtomicBool::new(true));
        let trail = OutputTrail::interrupted_by(flag);
        assert!(matches!(trail.create_dir_all(&root.join("d")), Err(Error::Engine(vrao_ao::Error::Interrupted))));
        assert!(!root.join("d").exists());
        std::fs::remove_dir_all(&root).unwrap();
    }
}
