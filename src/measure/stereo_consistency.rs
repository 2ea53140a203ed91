//! Stereo consistency (Wu 2025): of the surface points both eyes see, the share whose AO
//! differs between the eyes by more than [`AO_TOLERANCE`]. Each eye estimates its AO from
//! its own depth buffer, so where a kernel reaches past one eye's image edge, or sees a
//! different part of the scene, the eyes disagree and the disagreement shows as shimmer
//! or depth-less flatness in the headset, however small each eye's error is.
//!
//! For every pixel of eye A with a surface (depth > 0), the view-space point its depth
//! gives (`stereo::view_position_from_depth` at the pixel centre) is moved into eye B's
//! view space through world space and projected. The point counts as seen by both eyes
//! when it lands inside B's image and at least one of the four B pixels around it
//! (bilinear footprint) holds a surface whose view distance agrees with the point's
//! within [`DEPTH_AGREEMENT`] (relative): otherwise B sees something else there (an
//! occluder, the sky) or nothing at all. B's AO at the point is the bilinear blend of
//! those agreeing pixels (weights renormalised), so a smooth AO gradient does not count
//! as disagreement just because the eyes' pixel grids are offset. Both directions, left →
//! right and right → left, are pooled.
//!
//! Borders: [`BORDER_PX`] pixels. The *inner* (nasal) border of an eye is the edge on the
//! other eye's side, found from the other eye's position in this eye's view space (x > 0:
//! the right edge). On a headset the nasal half of each frustum is the narrower one (the
//! Vive-class profile: 45° towards the nose against ~52° outwards), and its border is
//! where one eye's screen-space samples leave the image while the other eye still sees the
//! scene there. *Interior* pixels are farther than [`BORDER_PX`] from every edge.

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use vrao_ao::Eye;

/// AO difference above which a point counts as inconsistent between the eyes.
pub const AO_TOLERANCE: f32 = 0.02;
/// Relative view-distance difference within which both eyes see the same surface.
pub const DEPTH_AGREEMENT: f64 = 0.01;
/// Width in pixels of the border bands.
pub const BORDER_PX: u32 = 40;

/// One eye's final images at full resolution, `width × height` row-major: reversed-Z
/// depth (0 on the sky) and the AO (one value a pixel).
#[derive(Clone, Copy, Debug)]
pub struct EyeImages<'a> {
    /// Reversed-Z depth, one value a pixel (0 on the sky).
    pub depth: &'a [f32],
    /// The final AO, one value a pixel.
    pub ao: &'a [f32],
}

/// Shares of the points seen by both eyes whose AO differs by more than [`AO_TOLERANCE`],
/// both directions pooled; `None` where no point was compared.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StereoConsistency {
    /// Over every compared point.
    pub inconsistent: Option<f64>,
    /// Over points within [`BORDER_PX`] of their eye's inner (nasal) edge.
    pub inner_border: Option<f64>,
    /// Over points farther than [`BORDER_PX`] from every edge of their eye's image.
    pub interior: Option<f64>,
    /// Points compared (both directions).
    pub compared: u64,
}

/// Which vertical edge of `eye`'s image faces `other`: true for the right edge.
pub fn inner_edge_is_right(eye: &Eye, other: &Eye) -> bool {
    eye.view_from_world().transform_point3(other.pose.position).x > 0.0
}

#[derive(Clone, Copy, Default)]
struct Counts {
    compared: [u64; 3],
    inconsistent: [u64; 3],
}

impl Counts {
    fn add(mut self, other: Counts) -> Counts {
        for k in 0..3 {
            self.compared[k] += other.compared[k];
            self.inconsistent[k] += other.inconsistent[k];
        }
        self
    }
}

/// The shares for two eyes (`eyes[0]` left, `eyes[1]` right) with `images` of `size`
/// pixels each and near plane `near`. Images of the wrong length give `None` shares.
pub fn stereo_consistency(eyes: &[Eye; 2], images: [EyeImages; 2], size: (u32, u32), near: f64) -> StereoConsistency {
    let pixels = size.0 as usize * size.1 as usize;
    let fits = images.iter().all(|i| i.depth.len() == pixels && i.ao.len() == pixels);
    let counts = if fits && pixels > 0 {
        direction(eyes, &images, 0, size, near).add(direction(eyes, &images, 1, size, near))
    } else {
        Counts::default()
    };
    let share = |k: usize| (counts.compared[k] > 0).then(|| counts.inconsistent[k] as f64 / counts.compared[k] as f64);
    StereoConsistency {
        inconsistent: share(0),
        inner_border: share(1),
        interior: share(2),
        compared: counts.compared[0],
    }
}

/// Eye `a`'s pixels looked up in the other eye.
fn direction(eyes: &[Eye; 2], images: &[EyeImages; 2], a: usize, size: (u32, u32), near: f64) -> Counts {
    let b = 1 - a;
    let (ea, eb) = (&eyes[a], &eyes[b]);
    let b_from_a = eb.view_from_world() * ea.pose.sanitized().world_from_local();
    let [l, r, u, d] = eb.fov.tangents();
    let (w, h) = (size.0 as usize, size.1 as usize);
    let inner_right = inner_edge_is_right(ea, eb);
    let border = BORDER_PX as usize;
    let (image_a, image_b) = (&images[a], &images[b]);
    (0..h)
        .into_par_iter()
        .map(|y| {
            let mut c = Counts::default();
            for x in 0..w {
                let depth = image_a.depth[y * w + x] as f64;
                if !(depth.is_finite() && depth > 0.0) {
                    continue;
                }
                let uv = [(x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64];
                let v = b_from_a.transform_point3(vrao_ao::Fov::view_position_from_depth(uv, depth, &ea.fov, near));
                let Some(ao_b) = lookup(image_b, v, [l, r, u, d], size, near) else {
                    continue;
                };
                let differs = (image_a.ao[y * w + x] - ao_b).abs() > AO_TOLERANCE;
                let inner = if inner_right { x + border >= w } else { x < border };
                let interior = x >= border && x + border < w && y >= border && y + border < h;
                for (k, member) in [true, inner, interior].into_iter().enumerate() {
                    if member {
                        c.compared[k] += 1;
                        c.inconsistent[k] += differs as u64;
                    }
                }
            }
            c
        })
        .reduce(Counts::default, Counts::add)
}

/// Eye B's AO at view-space point `v` (its view space), blended from the pixels around
/// it whose surface is `v`'s; `None` off the image or where B sees another surface.
pub(crate) fn lookup(image: &EyeImages, v: DVec3, [l, r, u, d]: [f64; 4], size: (u32, u32), near: f64) -> Option<f32> {
    let distance = -v.z;
    if distance.is_nan() || distance < near {
        return None;
    }
    let (s, t) = ((v.x / distance - l) / (r - l), (v.y / distance - u) / (d - u));
    if !(0.0..1.0).contains(&s) || !(0.0..1.0).contains(&t) {
        return None;
    }
    let (w, h) = (size.0 as i64, size.1 as i64);
    // Texel-centre coordinates: pixel i's centre is at i + 0.5.
    let (fx, fy) = (s * w as f64 - 0.5, t * h as f64 - 0.5);
    let (x0, y0) = (fx.floor() as i64, fy.floor() as i64);
    let (ax, ay) = (fx - x0 as f64, fy - y0 as f64);
    let (mut sum, mut weight) = (0.0f64, 0.0f64);
    for (dx, dy, wgt) in
        [(0, 0, (1.0 - ax) * (1.0 - ay)), (1, 0, ax * (1.0 - ay)), (0, 1, (1.0 - ax) * ay), (1, 1, ax * ay)]
    {
        let (x, y) = ((x0 + dx).clamp(0, w - 1) as usize, (y0 + dy).clamp(0, h - 1) as usize);
        let depth = image.depth[y * w as usize + x] as f64;
        if !(depth.is_finite() && depth > 0.0) {
            continue;
        }
        if ((near / depth - distance) / distance).abs() >= DEPTH_AGREEMENT {
            continue;
        }
        // A tiny weight still says "this pixel is the same surface".
        let wgt = wgt.max(1e-6);
        sum += wgt * image.ao[y * w as usize + x] as f64;
        weight += wgt;
    }
    (weight > 0.0).then(|| (sum / weight) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vrao_ao::HeadPose;
    use vrao_render::HeadsetProfile;

    const NEAR: f64 = 0.05;
    const SIZE: (u32, u32) = (120, 132);

    fn eyes() -> [Eye; 2] {
        let head = HeadPose::look_at(DVec3::new(0.3, 1.6, 2.0), DVec3::new(0.0, 1.2, -1.0)).unwrap();
        HeadsetProfile::with_size("test", SIZE.0, SIZE.1).eyes(&head, NEAR).eyes
    }

    /// Each eye's depth of the world plane z = −1 (facing +z) and an AO given by
    /// `ao(world point, eye index)`, at every pixel centre.
    fn render(eye: &Eye, index: usize, ao: impl Fn(DVec3, usize) -> f32) -> (Vec<f32>, Vec<f32>) {
        let [l, r, u, d] = eye.fov.tangents();
        let world_from_view = eye.pose.world_from_local();
        let (mut depth, mut values) = (Vec::new(), Vec::new());
        for y in 0..SIZE.1 {
            for x in 0..SIZE.0 {
                let (s, t) = ((x as f64 + 0.5) / SIZE.0 as f64, (y as f64 + 0.5) / SIZE.1 as f64);
                let dir_view = DVec3::new(l + (r - l) * s, u + (d - u) * t, -1.0);
                let origin = eye.pose.position;
                let dir = world_from_view.transform_vector3(dir_view);
                let hit = (-1.0 - origin.z) / dir.z;
                if hit > 0.0 {
                    // dir_view.z = −1: `hit` is the view distance.
                    depth.push((NEAR / hit) as f32);
                    values.push(ao(origin + dir * hit, index));
                } else {
                    depth.push(0.0);
                    values.push(1.0);
                }
            }
        }
        (depth, values)
    }

    fn consistency(ao: impl Fn(DVec3, usize) -> f32 + Copy) -> StereoConsistency {
        let eyes = eyes();
        let (dl, al) = render(&eyes[0], 0, ao);
        let (dr, ar) = render(&eyes[1], 1, ao);
        let images = [EyeImages { depth: &dl, ao: &al }, EyeImages { depth: &dr, ao: &ar }];
        stereo_consistency(&eyes, images, SIZE, NEAR)
    }

    #[test]
    fn the_same_ao_on_a_surface_in_both_eyes_is_consistent_everywhere() {
        // Constant, and varying smoothly over the plane (by ~0.05 per pixel here).
        for ao in [|_: DVec3, _| 0.7f32, |p: DVec3, _| (0.55 + 0.35 * (3.0 * p.x).sin() * (2.0 * p.y).cos()) as f32] {
            let c = consistency(ao);
            let pixels = 2 * SIZE.0 as u64 * SIZE.1 as u64;
            assert!(c.compared > pixels / 2, "{c:?}");
            assert_eq!(c.inconsistent, Some(0.0), "{c:?}");
            assert_eq!(c.inner_border, Some(0.0), "{c:?}");
            assert_eq!(c.interior, Some(0.0), "{c:?}");
        }
    }

    #[test]
    fn ao_that_differs_between_the_eyes_is_inconsistent_everywhere() {
        let c = consistency(|_, eye| if eye == 0 { 0.7 } else { 0.75 });
        assert_eq!((c.inconsistent, c.inner_border, c.interior), (Some(1.0), Some(1.0), Some(1.0)), "{c:?}");
        // Within the tolerance: consistent.
        let c = consistency(|_, eye| if eye == 0 { 0.7 } else { 0.715 });
        assert_eq!(c.inconsistent, Some(0.0), "{c:?}");
    }

    #[test]
    fn the_left_eyes_darkened_nasal_band_shows_in_half_the_inner_border_comparisons() {
        // The left eye writes AO 0.5 in its inner (right) 40 px and 1 elsewhere; the right
        // eye writes 1 everywhere. Left → right, every inner-border point differs (the
        // right eye sees all of them: its outward half reaches 52°, past the left eye's
        // 45° nasal edge). Right → left, the right eye's inner band looks at the left eye's
        // middle (AO 1): none differs. Both bands have as many points, so half differ.
        let eyes = eyes();
        let (dl, _) = render(&eyes[0], 0, |_, _| 1.0);
        let (dr, ar) = render(&eyes[1], 1, |_, _| 1.0);
        assert!(inner_edge_is_right(&eyes[0], &eyes[1]));
        let al: Vec<f32> =
            (0..dl.len()).map(|i| if (i % SIZE.0 as usize) as u32 + BORDER_PX >= SIZE.0 { 0.5 } else { 1.0 }).collect();
        let c = stereo_consistency(
            &eyes,
            [EyeImages { depth: &dl, ao: &al }, EyeImages { depth: &dr, ao: &ar }],
            SIZE,
            NEAR,
        );
        let inner = c.inner_border.unwrap();
        assert!((0.45..0.55).contains(&inner), "{c:?}");
        assert!(c.inconsistent.unwrap() < inner, "{c:?}");
    }

    #[test]
    fn the_inner_edge_is_towards_the_other_eye_and_its_half_frustum_is_the_narrower() {
        let eyes = eyes();
        assert!(inner_edge_is_right(&eyes[0], &eyes[1]), "the left eye's nasal edge is its right edge");
        assert!(!inner_edge_is_right(&eyes[1], &eyes[0]), "the right eye's nasal edge is its left edge");
        let [l, r, ..] = eyes[0].fov.tangents();
        assert!(r < -l, "left eye: nasal tangent {r} < temporal {}", -l);
        let [l, r, ..] = eyes[1].fov.tangents();
        assert!(-l < r, "right eye: nasal tangent {} < temporal {r}", -l);
    }

    #[test]
    fn a_surface_only_one_eye_sees_is_not_compared() {
        // The right eye's depth 5 % farther everywhere: no point agrees.
        let eyes = eyes();
        let (dl, al) = render(&eyes[0], 0, |_, _| 0.7);
        let (dr, ar) = render(&eyes[1], 1, |_, _| 0.2);
        let far: Vec<f32> = dr.iter().map(|d| d / 1.05).collect();
        let c = stereo_consistency(
            &eyes,
            [EyeImages { depth: &dl, ao: &al }, EyeImages { depth: &far, ao: &ar }],
            SIZE,
            NEAR,
        );
        assert_eq!((c.compared, c.inconsistent), (0, None), "{c:?}");
    }
}
