//! AO images side by side, to look at an estimate beside what it is scored against (the
//! reference tracer, the screen-space limits) rather than only at its figures.

use crate::error::{Error, Result};
use std::path::Path;

/// A `w × h` panel from values on a traced grid (every `stride`-th pixel, `grid` cells):
/// each pixel shows its grid cell's value, `cell(i, j)`, so a coarse grid reads as blocks.
pub fn grid_panel(w: usize, h: usize, stride: u32, grid: (u32, u32), cell: impl Fn(u32, u32) -> f32) -> Vec<f32> {
    let stride = stride.max(1);
    let (gw, gh) = (grid.0.max(1), grid.1.max(1));
    let mut panel = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            panel.push(cell((x as u32 / stride).min(gw - 1), (y as u32 / stride).min(gh - 1)));
        }
    }
    panel
}

/// Writes `panels` (AO in 0..=1, `w × h` each, row-major; a short panel reads as
/// unoccluded where it ends) left to right as one grey PNG at `path`.
pub fn save_panels(path: &Path, w: usize, h: usize, panels: &[Vec<f32>]) -> Result<()> {
    let width = w * panels.len();
    let mut pixels = vec![0u8; width * h];
    for (k, panel) in panels.iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let v = panel.get(y * w + x).copied().unwrap_or(1.0);
                pixels[y * width + k * w + x] = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
            }
        }
    }
    let refuse = |message: String| Error::Output { path: path.into(), message };
    let image = image::GrayImage::from_raw(width as u32, h as u32, pixels)
        .ok_or_else(|| refuse(format!("{width}x{h} pixels do not make an image")))?;
    image.save_with_format(path, image::ImageFormat::Png).map_err(|e| refuse(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_panel_repeats_each_cell_over_its_stride() {
        let panel = grid_panel(5, 3, 2, (3, 2), |i, j| (10 * j + i) as f32);
        assert_eq!(panel, [0.0, 0.0, 1.0, 1.0, 2.0, 0.0, 0.0, 1.0, 1.0, 2.0, 10.0, 10.0, 11.0, 11.0, 12.0]);
    }

    #[test]
    fn panels_are_written_left_to_right_in_grey() {
        let dir = std::env::temp_dir().join(format!("vrao-side-by-side-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.png");
        save_panels(&path, 2, 1, &[vec![0.0, 1.0], vec![0.5, 2.0]]).unwrap();
        let image = image::open(&path).unwrap().to_luma8();
        assert_eq!((image.width(), image.height()), (4, 1));
        assert_eq!(image.into_raw(), [0, 255, 128, 255]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
