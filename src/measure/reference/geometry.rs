//! The scene as the tracer sees it: every triangle in f32 relative to an f64 anchor, in
//! an obvhs compressed wide BVH (CWBVH8), with a watertight ray–triangle test and the
//! attributes the shading needs (vertex normals, uvs, material).

use crate::render::error::{Error, Result};
use crate::render::scene::{Scene, Texture};
use glam::{DVec3, Vec2, Vec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::sync::OnceLock;
use std::time::Duration;

/// A triangle's vertices relative to the anchor.
#[derive(Clone, Copy, Debug)]
struct Tri {
    p: [[f32; 3]; 3],
}

/// What shading needs of a triangle besides its positions.
#[derive(Clone, Copy, Debug)]
struct TriAttributes {
    normals: [Vec3; 3],
    uvs: [Vec2; 3],
    /// Unit normal of the winding, (v1 − v0) × (v2 − v0).
    geometric: Vec3,
    material: u32,
}

/// A material with its texture ready for sampling.
#[derive(Clone, Debug)]
pub(crate) struct SurfaceMaterial {
    pub diffuse: Vec3,
    pub emissive: Vec3,
    pub texture: Option<Texture>,
    /// Alpha factor and alpha-test cutoff: rays pass through texels whose alpha (factor
    /// × the texture's, filtered as the GPU filters it) is below the cutoff.
    pub alpha: f32,
    pub cutoff: Option<f32>,
}

impl SurfaceMaterial {
    /// Whether a ray passes through this material at `uv` (an alpha-tested hole).
    fn is_hole(&self, uv: Vec2) -> bool {
        let Some(cutoff) = self.cutoff else { return false };
        let alpha = self.alpha * self.texture.as_ref().map_or(1.0, |t| sample_alpha(t, uv));
        alpha < cutoff
    }
}

/// The closest hit along a ray: distance and barycentric weights of v1 and v2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    pub t: f32,
    pub prim: u32,
    pub b1: f32,
    pub b2: f32,
}

/// A hit point with its interpolated attributes, in anchored coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Surface {
    pub prim: u32,
    pub position: Vec3,
    /// Unit normal of the triangle's winding.
    pub geometric: Vec3,
    /// Interpolated vertex normal, normalised; the geometric normal when that is not usable.
    pub shading: Vec3,
    pub uv: Vec2,
    pub material: usize,
    /// Largest absolute coordinate of the triangle's vertices (the scale of f32 rounding there).
    pub magnitude: f32,
}

/// Every triangle of a scene in a BVH, relative to `anchor`.
pub(crate) struct SceneGeometry {
    bvh: Option<CwBvh>,
    /// In BVH leaf order, so that a leaf's primitive id indexes these directly.
    tris: Vec<Tri>,
    attributes: Vec<TriAttributes>,
    pub materials: Vec<SurfaceMaterial>,
    /// Whether some material is alpha-tested (rays then test each hit's alpha).
    has_holes: bool,
}

impl SceneGeometry {
    /// Flattens `scene` relative to `anchor` and builds the BVH. Triangles with a
    /// non-finite vertex or no area are left out (they rasterise to nothing); an index or
    /// material out of range is an input error.
    pub fn build(scene: &Scene, anchor: DVec3) -> Result<SceneGeometry> {
        // A scene that moves is traced frozen: callers pass `Scene::at_time` of the
        // frame's time; one that is not frozen is traced at time 0.
        let frozen;
        let scene = if scene.nodes.is_empty() {
            scene
        } else {
            frozen = scene.at_time(0.0);
            &frozen
        };
        let mut tris = Vec::with_capacity(scene.triangle_count());
        let mut attributes = Vec::with_capacity(scene.triangle_count());
        for mesh in &scene.meshes {
            if mesh.material >= scene.materials.len() {
                return Err(Error::input(format!(
                    "mesh '{}' uses material {} of {}",
                    mesh.name,
                    mesh.material,
                    scene.materials.len()
                )));
            }
            let offset = mesh.origin - anchor;
            let count = mesh.positions.len();
            let has_normals = mesh.normals.len() == count;
            let has_uvs = mesh.uvs.len() == count;
            for t in mesh.indices.chunks_exact(3) {
                let idx = [t[0] as usize, t[1] as usize, t[2] as usize];
                if idx.iter().any(|&i| i >= count) {
                    return Err(Error::input(format!(
                        "mesh '{}' has a triangle index out of range ({:?} of {count} vertices)",
                        mesh.name, idx
                    )));
                }
                let p = idx.map(|i| (offset + mesh.positions[i].as_dvec3()).as_vec3());
                let geometric = (p[1] - p[0]).cross(p[2] - p[0]);
                let length = geometric.length();
                if !(p.iter().all(|v| v.is_finite()) && length > 0.0 && length.is_finite()) {
                    continue;
                }
                tris.push(Tri { p: p.map(|v| v.to_array()) });
                attributes.push(TriAttributes {
                    normals: idx.map(|i| if has_normals { mesh.normals[i] } else { Vec3::ZERO }),
                    uvs: idx.map(|i| if has_uvs { mesh.uvs[i] } else { Vec2::ZERO }),
                    geometric: geometric / length,
                    material: mesh.material as u32,
                });
            }
        }
        let bvh = if tris.is_empty() {
            None
        } else {
            let boxes: Vec<Triangle> =
                tris.iter().map(|t| Triangle { v0: t.p[0].into(), v1: t.p[1].into(), v2: t.p[2].into() }).collect();
            let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            );
            // Store the triangles in leaf order (without pre-splits this is a permutation).
            tris = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
            attributes = bvh.primitive_indices.iter().map(|&i| attributes[i as usize]).collect();
            Some(bvh)
        };
        let materials: Vec<SurfaceMaterial> = scene
            .materials
            .iter()
            .map(|m| SurfaceMaterial {
                diffuse: m.diffuse,
                emissive: m.emissive,
                texture: m.diffuse_texture.clone().filter(|t| {
                    t.width > 0 && t.height > 0 && t.rgba8.len() as u64 == 4 * t.width as u64 * t.height as u64
                }),
                alpha: m.alpha,
                cutoff: m.alpha_cutoff(),
            })
            .collect();
        let has_holes = materials.iter().any(|m| m.cutoff.is_some());
        Ok(SceneGeometry { bvh, tris, attributes, materials, has_holes })
    }

    #[cfg(test)]
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The uv at barycentrics (b1, b2) of leaf-order triangle `prim`.
    fn uv_at(&self, prim: usize, b1: f32, b2: f32) -> Vec2 {
        let a = &self.attributes[prim];
        a.uvs[0] * (1.0 - b1 - b2) + a.uvs[1] * b1 + a.uvs[2] * b2
    }

    /// The closest hit with t in (`tmin`, `tmax`) along unit `dir` from `origin`, ignoring
    /// triangle `skip` (`u32::MAX` for none) and alpha-tested holes.
    pub fn closest(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32, skip: u32) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        // obvhs's box test takes the sign of a zero component from its bits but selects the
        // near and far planes by `< 0`: a −0.0 would miss every box. Adding +0.0 makes it +0.0.
        let dir = dir + Vec3::ZERO;
        let pre = RayPrecomputed::new(origin, dir);
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), tmin, tmax);
        let mut best: Option<Hit> = None;
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |ray, id| {
            if id as u32 == skip {
                return f32::INFINITY;
            }
            // The traversal keeps a hit only when it is strictly closer than its tmax.
            match pre.intersect(&self.tris[id], ray.tmin, ray.tmax) {
                Some((_, b1, b2)) if self.has_holes && self.is_hole(id, b1, b2) => f32::INFINITY,
                Some((t, b1, b2)) if t < ray.tmax => {
                    best = Some(Hit { t, prim: id as u32, b1, b2 });
                    t
                }
                _ => f32::INFINITY,
            }
        });
        // The traversal accepted exactly the hits recorded, each closer than the last.
        debug_assert!(best.is_none_or(|b| hit.t == b.t && hit.primitive_id == b.prim));
        best
    }

    /// Whether the hit at (b1, b2) of `prim` falls in an alpha-tested hole.
    fn is_hole(&self, prim: usize, b1: f32, b2: f32) -> bool {
        let material = &self.materials[self.attributes[prim].material as usize];
        material.cutoff.is_some() && material.is_hole(self.uv_at(prim, b1, b2))
    }

    /// The attributes at `hit`.
    pub fn surface(&self, hit: &Hit) -> Surface {
        let tri = &self.tris[hit.prim as usize];
        let a = &self.attributes[hit.prim as usize];
        let [p0, p1, p2] = tri.p.map(Vec3::from);
        let (b1, b2) = (hit.b1, hit.b2);
        let b0 = 1.0 - b1 - b2;
        let position = p0 + (p1 - p0) * b1 + (p2 - p0) * b2;
        let n = a.normals[0] * b0 + a.normals[1] * b1 + a.normals[2] * b2;
        let shading = n.try_normalize().unwrap_or(a.geometric);
        let uv = a.uvs[0] * b0 + a.uvs[1] * b1 + a.uvs[2] * b2;
        let magnitude = p0.abs().max(p1.abs()).max(p2.abs()).max_element();
        Surface {
            prim: hit.prim,
            position,
            geometric: a.geometric,
            shading,
            uv,
            material: a.material as usize,
            magnitude,
        }
    }
}

/// Per-ray constants of the watertight ray–triangle test (Woop, Benthin and Wald 2013,
/// "Watertight Ray/Triangle Intersection"): the axis along which the direction is largest
/// becomes z, and a shear maps the ray onto the +z axis, so that the edge tests of two
/// triangles sharing an edge are computed from the same numbers and no ray slips between.
struct RayPrecomputed {
    origin: [f32; 3],
    k: [usize; 3],
    shear: [f32; 3],
}

impl RayPrecomputed {
    fn new(origin: Vec3, dir: Vec3) -> Self {
        let d = dir.to_array();
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the winding of the sheared triangle: swap when the ray points down its axis.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        RayPrecomputed {
            origin: origin.to_array(),
            k: [kx, ky, kz],
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        }
    }

    /// (t, b1, b2) for a hit with tmin < t < tmax; b1 and b2 weight v1 and v2.
    #[inline]
    fn intersect(&self, tri: &Tri, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let rel = |v: &[f32; 3]| [v[kx] - self.origin[kx], v[ky] - self.origin[ky], v[kz] - self.origin[kz]];
        let (a, b, c) = (rel(&tri.p[0]), rel(&tri.p[1]), rel(&tri.p[2]));
        let (ax, ay) = (a[0] - sx * a[2], a[1] - sy * a[2]);
        let (bx, by) = (b[0] - sx * b[2], b[1] - sy * b[2]);
        let (cx, cy) = (c[0] - sx * c[2], c[1] - sy * c[2]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // On an edge in f32: decide it in f64, where these products are exact.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let f = |x: f32| x as f64;
            u = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
            v = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
            w = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let t_scaled = u * (sz * a[2]) + v * (sz * b[2]) + w * (sz * c[2]);
        let t = t_scaled / det;
        if !(t > tmin && t < tmax) {
            return None;
        }
        Some((t, v / det, w / det))
    }
}

/// sRGB-encoded byte → linear value.
fn srgb_to_linear(byte: u8) -> f32 {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let linear = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
            linear as f32
        })
    })[byte as usize]
}

/// Bilinear filtering of `texture` at `uv`, repeating in u and clamping in v; v = 0 is the
/// top row ([`crate::render::scene::Mesh::uvs`]). `texel` reads the texel at a byte offset
/// into `rgba8`; `lerp` blends two of them.
fn bilinear<T: Copy>(texture: &Texture, uv: Vec2, texel: impl Fn(usize) -> T, lerp: impl Fn(T, T, f32) -> T) -> T {
    let (w, h) = (texture.width as i64, texture.height as i64);
    let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
    let x = uv.x as f64 * w as f64 - 0.5;
    let y = (uv.y as f64 * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let at = |x: i64, y: i64| texel(4 * (y.clamp(0, h - 1) * w + x.rem_euclid(w)) as usize);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let top = lerp(at(x0, y0), at(x0 + 1, y0), fx);
    let bottom = lerp(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx);
    lerp(top, bottom, fy)
}

/// Bilinear lookup of an sRGB texture (decoded to linear before filtering, as an sRGB
/// texture format does), addressed as [`bilinear`] says.
pub(crate) fn sample_texture(texture: &Texture, uv: Vec2) -> Vec3 {
    let texel = |i: usize| {
        let b = &texture.rgba8[i..i + 3];
        Vec3::new(srgb_to_linear(b[0]), srgb_to_linear(b[1]), srgb_to_linear(b[2]))
    };
    bilinear(texture, uv, texel, Vec3::lerp)
}

/// Bilinear lookup of a texture's alpha (linear bytes, as the GPU filters them),
/// addressed as [`bilinear`] says.
pub(crate) fn sample_alpha(texture: &Texture, uv: Vec2) -> f32 {
    let texel = |i: usize| texture.rgba8[i + 3] as f32 / 255.0;
    bilinear(texture, uv, texel, |a, b, t| a + (b - a) * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::{HeadPath, Material, Mesh};
    use crate::render::stereo::HeadPose;

    fn quad_scene(origin: DVec3) -> Scene {
        // Two triangles sharing the diagonal of the unit square in z = 0 (around `origin`).
        let positions = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        Scene {
            name: "quad".into(),
            meshes: vec![Mesh {
                colors: Vec::new(),
                tangents: Vec::new(),
                name: "quad".into(),
                origin,
                normals: vec![Vec3::Z; 4],
                uvs: vec![Vec2::ZERO; 4],
                positions,
                indices: vec![0, 1, 2, 0, 2, 3],
                material: 0,
                node: None,
            }],
            materials: vec![Material::plain("white", Vec3::ONE)],
            lights: vec![],
            environment: None,
            head: HeadPath::fixed(HeadPose::IDENTITY),
            nodes: Vec::new(),
        }
    }

    #[test]
    fn rays_through_a_shared_edge_never_slip_through() {
        let g = SceneGeometry::build(&quad_scene(DVec3::ZERO), DVec3::ZERO).unwrap();
        assert_eq!(g.triangle_count(), 2);
        // Rays aimed exactly at points of the shared diagonal and at the shared vertices.
        for i in 0..=200 {
            let s = i as f32 / 200.0;
            for target in [Vec3::new(s, s, 0.0), Vec3::new(s, 1.0 - s, 0.0)] {
                let origin = Vec3::new(0.3, -0.2, 2.0);
                let dir = (target - origin).normalize();
                let hit = g.closest(origin, dir, 0.0, 10.0, u32::MAX);
                let hit = hit.unwrap_or_else(|| panic!("ray to {target} missed"));
                let p = g.surface(&hit).position;
                assert!((p - target).length() < 1e-5, "{p} vs {target}");
            }
        }
        // Outside the square: a miss; behind the origin: a miss; tmax respected.
        assert!(g.closest(Vec3::new(1.5, 0.5, 1.0), -Vec3::Z, 0.0, 10.0, u32::MAX).is_none());
        assert!(g.closest(Vec3::new(0.5, 0.5, 1.0), Vec3::Z, 0.0, 10.0, u32::MAX).is_none());
        assert!(g.closest(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z, 0.0, 1.0, u32::MAX).is_none());
        let hit = g.closest(Vec3::new(0.5, 0.25, 1.0), -Vec3::Z, 0.0, 1.001, u32::MAX).unwrap();
        assert_eq!(hit.t, 1.0);
        // Skipping the triangle that is hit leaves nothing.
        assert!(g.closest(Vec3::new(0.5, 0.25, 1.0), -Vec3::Z, 0.0, 2.0, hit.prim).is_none());
        // From below, the same face is hit from its back.
        let back = g.closest(Vec3::new(0.5, 0.25, -1.0), Vec3::Z, 0.0, 2.0, u32::MAX).unwrap();
        assert_eq!((back.t, back.prim), (1.0, hit.prim));
        let s = g.surface(&back);
        assert_eq!(s.geometric, Vec3::Z);
        assert_eq!(s.shading, Vec3::Z);
    }

    #[test]
    fn geometry_far_from_the_origin_is_precise_relative_to_the_anchor() {
        let far = DVec3::new(1e5, -2e5, 3e5);
        let g = SceneGeometry::build(&quad_scene(far), far + DVec3::new(0.5, 0.5, 3.0)).unwrap();
        let hit = g.closest(Vec3::new(0.1, -0.2, 0.0), -Vec3::Z, 0.0, 10.0, u32::MAX);
        assert!((hit.unwrap().t - 3.0).abs() < 1e-6);
    }

    #[test]
    fn degenerate_and_non_finite_triangles_are_left_out_and_bad_indices_are_errors() {
        let mut scene = quad_scene(DVec3::ZERO);
        scene.meshes[0].positions.push(Vec3::new(f32::NAN, 0.0, 0.0));
        scene.meshes[0].normals.push(Vec3::Z);
        scene.meshes[0].uvs.push(Vec2::ZERO);
        scene.meshes[0].indices.extend([0, 1, 4, 0, 0, 1, 0, 1, 1]);
        assert_eq!(SceneGeometry::build(&scene, DVec3::ZERO).unwrap().triangle_count(), 2);
        scene.meshes[0].indices.extend([0, 1, 9]);
        assert!(SceneGeometry::build(&scene, DVec3::ZERO).is_err());
        let mut empty = quad_scene(DVec3::ZERO);
        empty.meshes.clear();
        let g = SceneGeometry::build(&empty, DVec3::ZERO).unwrap();
        assert!(g.closest(Vec3::ZERO, Vec3::X, 0.0, 1.0, u32::MAX).is_none());
    }

    #[test]
    fn textures_decode_srgb_and_filter_bilinearly() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        assert!((srgb_to_linear(188) - 0.5).abs() < 0.01);
        // 2×2: top row black/white, bottom row red/green.
        let rgba8 = vec![0, 0, 0, 255, 255, 255, 255, 255, 255, 0, 0, 255, 0, 255, 0, 255];
        let t = Texture { sampling: Default::default(), width: 2, height: 2, rgba8, source: None };
        assert_eq!(sample_texture(&t, Vec2::new(0.25, 0.25)), Vec3::ZERO);
        assert_eq!(sample_texture(&t, Vec2::new(0.75, 0.25)), Vec3::ONE);
        assert_eq!(sample_texture(&t, Vec2::new(0.25, 0.75)), Vec3::X);
        // Halfway between the top texels; wrapping in u at the left edge.
        assert!((sample_texture(&t, Vec2::new(0.5, 0.25)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert!((sample_texture(&t, Vec2::new(0.0, 0.25)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert!(sample_texture(&t, Vec2::new(f32::NAN, 7.0)).is_finite());
    }
}
