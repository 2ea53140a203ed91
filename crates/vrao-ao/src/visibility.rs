//! The headset's visibility mask and foveation as one map.
//!
//! A lens shows only part of each eye's rectangle; runtimes describe the rest as a
//! hidden-area mesh (OpenXR's `XR_KHR_visibility_mask`, OpenVR's hidden area mesh):
//! triangles on the view's image plane at unit distance, in the tangents of the view
//! angles (x right, y up). [`ViewMask`] holds one view's, from the runtime or from a
//! headset profile; [`ViewMask::coverage`] rasterises it for a view's pixels.
//!
//! The passes read the result as one map per view ([`RateMap`]): for every 8×8 tile of
//! full-resolution pixels the share of the full sample count its pixels spend — 0 where
//! the lens hides the whole tile, the foveation rate of the tile's centre elsewhere — and
//! for every 16×16 tile the same at its second level (the tiles of a half-resolution
//! pass's 8×8 workgroups, and of the quad passes'). A compute pass reads its tile once and
//! leaves a hidden tile before any fetch; the raster passes are kept off hidden pixels by
//! the per-pixel coverage drawn into depth first.

use crate::error::{Error, Result};
use crate::settings::FoveationMap;
use glam::Vec2;

/// Full-resolution pixels on a side of one tile of [`RateMap`]'s first level (a full
/// resolution workgroup's 8×8 pixels).
pub(crate) const TILE_PIXELS: u32 = 8;

/// The most triangles one view's mask may hold (runtimes give tens to a few hundred).
pub(crate) const MAX_MASK_TRIANGLES: usize = 65_536;

/// Where a mask's triangles lie: on the pixels the lens hides, or on those it shows.
#[derive(Clone, Debug, PartialEq)]
enum Covers {
    Hidden,
    Visible,
}

/// One view's visibility mask: triangles on its image plane at unit distance, in the
/// tangents of the view angles (x right, y up), as `xrGetVisibilityMaskKHR` returns them.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewMask {
    covers: Covers,
    triangles: Vec<[Vec2; 3]>,
    /// Where the mask comes from (a runtime, a profile's published figure, a default),
    /// for reports.
    pub source: String,
}

impl ViewMask {
    /// The most triangles one view's mask takes (`MAX_MASK_TRIANGLES`).
    pub const MAX_TRIANGLES: usize = MAX_MASK_TRIANGLES;

    /// A mask from a runtime's hidden triangle mesh (indexed, three indices a triangle).
    /// Indices out of range, a count that is not a multiple of three, too many triangles
    /// or a vertex that is not finite is `Error::Input`.
    pub fn from_hidden_mesh(vertices: &[Vec2], indices: &[u32], source: impl Into<String>) -> Result<ViewMask> {
        Ok(ViewMask { covers: Covers::Hidden, triangles: triangles_of(vertices, indices)?, source: source.into() })
    }

    /// A mask from a runtime's visible triangle mesh: every pixel outside it is hidden.
    pub fn from_visible_mesh(vertices: &[Vec2], indices: &[u32], source: impl Into<String>) -> Result<ViewMask> {
        Ok(ViewMask { covers: Covers::Visible, triangles: triangles_of(vertices, indices)?, source: source.into() })
    }

    /// What Monado gives a device without a mask of its own: the field of view's four
    /// corners cut off, each a right triangle an eighth of the rectangle's width and height
    /// on its legs (`tangents`: tan left, right, up, down).
    pub fn corner_cut(tangents: [f64; 4]) -> ViewMask {
        // Corners in the rectangle's own coordinates (−1..1 on each axis).
        let corner = |sx: f32, sy: f32| {
            [Vec2::new(sx, sy), Vec2::new(sx, sy * 0.75), Vec2::new(sx * 0.75, sy)]
                .map(|c| unit_to_tangent(c, tangents))
        };
        ViewMask {
            covers: Covers::Hidden,
            triangles: vec![corner(1.0, 1.0), corner(-1.0, 1.0), corner(-1.0, -1.0), corner(1.0, -1.0)],
            source: "Monado's default from the field of view (the corners cut off)".into(),
        }
    }

    /// A lens whose visible region is the superellipse |x|ⁿ + |y|ⁿ ≤ 1 in the rectangle's
    /// own coordinates (−1..1 from edge to edge), as a fan of `segments` triangles; `n` = 2
    /// is the ellipse touching the four edges, larger `n` squarer.
    pub fn superellipse(tangents: [f64; 4], n: f64, segments: u32, source: impl Into<String>) -> ViewMask {
        let segments = segments.clamp(8, 1024);
        let point = |i: u32| {
            let a = i as f64 / segments as f64 * std::f64::consts::TAU;
            let (s, c) = a.sin_cos();
            let x = c.signum() * c.abs().powf(2.0 / n);
            let y = s.signum() * s.abs().powf(2.0 / n);
            unit_to_tangent(Vec2::new(x as f32, y as f32), tangents)
        };
        let centre = unit_to_tangent(Vec2::ZERO, tangents);
        let triangles = (0..segments).map(|i| [centre, point(i), point(i + 1)]).collect();
        ViewMask { covers: Covers::Visible, triangles, source: source.into() }
    }

    /// Whether the mask hides nothing at all (no triangles of a hidden mesh).
    pub fn is_empty(&self) -> bool {
        self.covers == Covers::Hidden && self.triangles.is_empty()
    }

    /// Which of a `width` × `height` view's pixels the lens shows (255) or hides (0), row
    /// by row from the top, for the frustum `tangents` (tan left, right, up, down): a pixel
    /// is hidden when its centre lies inside a hidden triangle (outside every visible one).
    pub fn coverage(&self, width: u32, height: u32, tangents: [f64; 4]) -> Vec<u8> {
        let (fill, background) = match self.covers {
            Covers::Hidden => (0u8, 255u8),
            Covers::Visible => (255u8, 0u8),
        };
        let mut pixels = vec![background; width as usize * height as usize];
        let [left, right, up, down] = tangents;
        // Pixel coordinates (pixel centres at +0.5) of a point on the image plane.
        let to_pixel = |t: Vec2| {
            glam::DVec2::new(
                (t.x as f64 - left) / (right - left) * width as f64,
                (t.y as f64 - up) / (down - up) * height as f64,
            )
        };
        for triangle in &self.triangles {
            let [a, b, c] = triangle.map(to_pixel);
            let area = (b - a).perp_dot(c - a);
            if !area.is_finite() || area == 0.0 {
                continue;
            }
            let min = a.min(b).min(c);
            let max = a.max(b).max(c);
            let x0 = (min.x - 0.5).ceil().max(0.0) as u32;
            let y0 = (min.y - 0.5).ceil().max(0.0) as u32;
            let x1 = ((max.x - 0.5).floor().min(width as f64 - 1.0)).max(-1.0);
            let y1 = ((max.y - 0.5).floor().min(height as f64 - 1.0)).max(-1.0);
            if x1 < 0.0 || y1 < 0.0 {
                continue;
            }
            let sign = area.signum();
            for y in y0..=y1 as u32 {
                for x in x0..=x1 as u32 {
                    let p = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    // Inside (edges included) whatever the triangle's winding.
                    let inside =
                        [(a, b), (b, c), (c, a)].iter().all(|&(e0, e1)| (e1 - e0).perp_dot(p - e0) * sign >= 0.0);
                    if inside {
                        pixels[(y * width + x) as usize] = fill;
                    }
                }
            }
        }
        pixels
    }

    /// The share of a `width` × `height` view's pixels the mask hides.
    pub fn hidden_share(&self, width: u32, height: u32, tangents: [f64; 4]) -> f64 {
        let pixels = self.coverage(width, height, tangents);
        pixels.iter().filter(|&&p| p == 0).count() as f64 / pixels.len().max(1) as f64
    }
}

/// A point of the rectangle's own coordinates (−1..1 left to right, bottom to top) on the
/// image plane of the frustum `tangents`.
fn unit_to_tangent(u: Vec2, [left, right, up, down]: [f64; 4]) -> Vec2 {
    Vec2::new(
        (left + (u.x as f64 * 0.5 + 0.5) * (right - left)) as f32,
        (down + (u.y as f64 * 0.5 + 0.5) * (up - down)) as f32,
    )
}

fn triangles_of(vertices: &[Vec2], indices: &[u32]) -> Result<Vec<[Vec2; 3]>> {
    if !indices.len().is_multiple_of(3) {
        return Err(Error::input(format!("visibility mask: {} indices, not a multiple of 3", indices.len())));
    }
    if indices.len() / 3 > MAX_MASK_TRIANGLES {
        return Err(Error::input(format!(
            "visibility mask: {} triangles (at most {MAX_MASK_TRIANGLES})",
            indices.len() / 3
        )));
    }
    if let Some(v) = vertices.iter().find(|v| !v.is_finite() || v.abs().max_element() > 1e6) {
        return Err(Error::input(format!("visibility mask: vertex {v} is not a finite tangent below 1e6")));
    }
    indices
        .chunks_exact(3)
        .map(|t| {
            let vertex = |i: u32| {
                vertices.get(i as usize).copied().ok_or_else(|| {
                    Error::input(format!("visibility mask: index {i} beyond its {} vertices", vertices.len()))
                })
            };
            Ok([vertex(t[0])?, vertex(t[1])?, vertex(t[2])?])
        })
        .collect()
}

/// A visibility mask for each view of a headset (left, then right).
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityMask {
    /// One mask per view, in view order.
    pub views: Vec<ViewMask>,
}

/// One view's map: per tile the share of the full sample count its pixels spend (0: the
/// lens hides the whole tile), as bytes (255 = 1), at two tile sizes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RateMap {
    /// Tiles per row of the first level (8×8 pixels each), even so that the second
    /// level's tiles are exactly 2×2 of them.
    pub width: u32,
    /// Tile rows of the first level (even).
    pub height: u32,
    /// The first level, row by row.
    pub tiles: Vec<u8>,
    /// The second level (16×16 pixels a tile): width/2 × height/2.
    pub coarse: Vec<u8>,
}

impl RateMap {
    /// The map of a `width` × `height` view with frustum `tangents`, its pixels' coverage
    /// ([`ViewMask::coverage`]; `None`: every pixel shown) and `foveation`.
    pub(crate) fn new(
        width: u32,
        height: u32,
        tangents: [f64; 4],
        coverage: Option<&[u8]>,
        foveation: &FoveationMap,
    ) -> Self {
        let tiles_x = width.div_ceil(2 * TILE_PIXELS) * 2;
        let tiles_y = height.div_ceil(2 * TILE_PIXELS) * 2;
        let [left, right, up, down] = tangents;
        let (inner, outer) = (foveation.full_rate_deg.to_radians().tan(), foveation.edge_deg.to_radians().tan());
        // The foveation rate at full-resolution pixel coordinates (x, y), from the angle off
        // the view axis (`FoveationMap::rate`, in tangents as the shaders did per pixel).
        let rate_at = |x: f64, y: f64| -> f32 {
            if foveation.edge_rate >= 1.0 {
                return 1.0;
            }
            let tx = left + (x / width as f64).clamp(0.0, 1.0) * (right - left);
            let ty = up + (y / height as f64).clamp(0.0, 1.0) * (down - up);
            let tan = (tx * tx + ty * ty).sqrt() as f32;
            let t = ((tan - inner) / (outer - inner).max(1e-6)).clamp(0.0, 1.0);
            1.0 + (foveation.edge_rate - 1.0) * t
        };
        // Where the view axis meets the image, in pixels (it may lie outside).
        let axis = glam::DVec2::new(-left / (right - left) * width as f64, -up / (down - up) * height as f64);
        // Whether any pixel of the block at (x0, y0) of `size` pixels is shown.
        let shown = |x0: u32, y0: u32, size: u32| -> bool {
            let Some(coverage) = coverage else { return x0 < width && y0 < height };
            (y0..(y0 + size).min(height)).any(|y| {
                let row = &coverage[(y * width) as usize..((y + 1) * width) as usize];
                row[(x0.min(width) as usize)..((x0 + size).min(width) as usize)].iter().any(|&p| p != 0)
            })
        };
        let level = |tile: u32, nx: u32, ny: u32| -> Vec<u8> {
            let mut out = Vec::with_capacity((nx * ny) as usize);
            for ty in 0..ny {
                for tx in 0..nx {
                    let (x0, y0) = (tx * tile, ty * tile);
                    out.push(if shown(x0, y0, tile) {
                        // The rate of the tile's point nearest the view axis: a pixel within
                        // the full-rate cone keeps its full count whatever tile it lies in.
                        let nearest_x = axis.x.clamp(x0 as f64, (x0 + tile) as f64);
                        let nearest_y = axis.y.clamp(y0 as f64, (y0 + tile) as f64);
                        let rate = rate_at(nearest_x, nearest_y);
                        // A shown tile never reads 0, whatever its rate rounds to.
                        ((rate * 255.0).round() as u8).max(1)
                    } else {
                        0
                    });
                }
            }
            out
        };
        RateMap {
            width: tiles_x,
            height: tiles_y,
            tiles: level(TILE_PIXELS, tiles_x, tiles_y),
            coarse: level(2 * TILE_PIXELS, tiles_x / 2, tiles_y / 2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Foveation;

    const SQUARE: [f64; 4] = [-1.0, 1.0, 1.0, -1.0];

    #[test]
    fn monado_corner_cut_hides_four_triangles_of_one_thirty_second_each() {
        // Each corner triangle has legs of a quarter of the half-width: area 1/32 of the
        // rectangle's quarter, so 4 × (0.25 × 0.25 / 2) / 4 = 3.125 % of it.
        let mask = ViewMask::corner_cut(SQUARE);
        let share = mask.hidden_share(400, 400, SQUARE);
        assert!((share - 0.03125).abs() < 0.002, "{share}");
        // An asymmetric frustum keeps the share (the cut follows the rectangle).
        let asym = [-1.4, 0.8, 1.1, -1.2];
        let share = ViewMask::corner_cut(asym).hidden_share(300, 420, asym);
        assert!((share - 0.03125).abs() < 0.003, "{share}");
    }

    #[test]
    fn the_ellipse_touching_the_edges_hides_one_minus_a_quarter_pi() {
        let mask = ViewMask::superellipse(SQUARE, 2.0, 512, "test");
        let share = mask.hidden_share(500, 500, SQUARE);
        let expected = 1.0 - std::f64::consts::FRAC_PI_4;
        assert!((share - expected).abs() < 0.003, "{share} vs {expected}");
    }

    #[test]
    fn hidden_and_visible_meshes_of_the_same_split_are_complements() {
        let v = [Vec2::new(-1.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(-1.0, -1.0), Vec2::new(1.0, -1.0)];
        // The upper-left triangle hidden, or the lower-right one visible: the same pixels.
        let hidden = ViewMask::from_hidden_mesh(&v, &[0, 1, 2], "h").unwrap().coverage(64, 64, SQUARE);
        let visible = ViewMask::from_visible_mesh(&v, &[1, 3, 2], "v").unwrap().coverage(64, 64, SQUARE);
        let differing = hidden.iter().zip(&visible).filter(|(a, b)| a != b).count();
        // Pixel centres on the shared diagonal count for both.
        assert!(differing <= 64, "{differing}");
        assert_eq!(hidden[0], 0, "top-left hidden");
        assert_eq!(hidden[64 * 64 - 1], 255, "bottom-right shown");
    }

    #[test]
    fn bad_meshes_are_input_errors() {
        let v = [Vec2::ZERO, Vec2::X, Vec2::Y];
        assert!(ViewMask::from_hidden_mesh(&v, &[0, 1], "x").is_err());
        assert!(ViewMask::from_hidden_mesh(&v, &[0, 1, 3], "x").is_err());
        assert!(ViewMask::from_hidden_mesh(&[Vec2::NAN, Vec2::X, Vec2::Y], &[0, 1, 2], "x").is_err());
    }

    #[test]
    fn the_rate_map_is_zero_on_hidden_tiles_and_follows_foveation_elsewhere() {
        let (w, h) = (160, 160);
        let mask = ViewMask::superellipse(SQUARE, 2.0, 256, "test");
        let coverage = mask.coverage(w, h, SQUARE);
        let map = RateMap::new(w, h, SQUARE, Some(&coverage), &Foveation::High.map());
        assert_eq!((map.width, map.height), (20, 20));
        assert_eq!(map.tiles[0], 0, "the corner tile lies outside the ellipse");
        let centre = map.tiles[(10 * map.width + 10) as usize];
        assert_eq!(centre, 255, "full rate on the axis");
        // Off the axis at 45° (tangent 1) high foveation's floor of one half.
        let edge = map.tiles[(10 * map.width + 1) as usize];
        assert!((edge as f32 / 255.0 - 0.5).abs() < 0.02, "{edge}");
        // The coarse level agrees: hidden corner, full centre.
        assert_eq!(map.coarse[0], 0);
        assert_eq!(map.coarse[(5 * map.width / 2 + 5) as usize], 255);
        // Without a mask and foveation every tile is at full rate, padding included.
        let open = RateMap::new(w, h, SQUARE, None, &Foveation::Off.map());
        assert!(open.tiles.iter().all(|&t| t == 255));
    }

    #[test]
    fn a_partly_shown_tile_is_not_skipped() {
        // One shown pixel in the last tile of the first row.
        let (w, h) = (20, 9);
        let mut coverage = vec![0u8; (w * h) as usize];
        coverage[19] = 255;
        let map = RateMap::new(w, h, SQUARE, Some(&coverage), &Foveation::Off.map());
        assert_eq!(map.width, 4, "padded to even tiles");
        assert_eq!(&map.tiles[..4], &[0, 0, 255, 0]);
        assert_eq!(map.coarse[1], 255);
        assert_eq!(map.coarse[0], 0);
    }
}
