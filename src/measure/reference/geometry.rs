//! The scene as the tracer sees it: every triangle in f32 relative to an f64 anchor, in
//! an obvhs compressed wide BVH (CWBVH8), with a watertight ray–triangle test and the
//! attributes the shading needs (vertex normals, uvs, vertex colours, tangents, material).
//!
//! Textures are read as the G-buffer reads them: the mesh's uv moved by the texture's
//! `KHR_texture_transform` ([`Sampling::place`]), then wrapped per axis (repeat, mirrored
//! repeat or clamp) and filtered with its magnification filter (nearest or bilinear) at the
//! full-size level. The tracer has no pixel footprint (a bounce ray's hit has none, and a
//! primary ray's is one pixel of whatever size), so it never minifies or picks a mip level:
//! where the GPU minifies, its mip average and the tracer's full-size texel differ as the
//! texture's detail does.

use crate::error::{Error, Result};
use glam::{DVec3, Vec2, Vec3, Vec3A, Vec4};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::sync::OnceLock;
use std::time::Duration;
use vrao_render::scene::{Filter, Material, Mesh, Sampling, Scene, Texture};

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
    /// Index into [`SceneGeometry::extras`], or [`NO_EXTRAS`] for a triangle of a mesh
    /// with neither vertex colours nor tangents (white, no normal texture).
    extras: u32,
}

/// [`TriAttributes::extras`] of a triangle with none.
const NO_EXTRAS: u32 = u32::MAX;

/// The per-vertex attributes few meshes have, kept beside the rest so that the triangles
/// of meshes without them cost nothing more.
#[derive(Clone, Copy, Debug)]
struct TriExtras {
    /// Linear RGBA vertex colours (white where the mesh has none).
    colors: [Vec4; 3],
    /// Tangents with the bitangent's sign in w (zero where the mesh has none or its
    /// material no normal texture).
    tangents: [Vec4; 3],
    /// Texture coordinates of set 1 (set 0's where the mesh has none).
    uvs1: [Vec2; 3],
}

/// A material with its textures ready for sampling.
#[derive(Clone, Debug)]
pub(crate) struct SurfaceMaterial {
    pub diffuse: Vec3,
    pub emissive: Vec3,
    /// The base colour texture (sRGB; alpha linear).
    pub texture: Option<Texture>,
    /// The emission texture (sRGB), multiplying `emissive`.
    pub emissive_texture: Option<Texture>,
    /// The tangent-space normal texture (linear) and its scale.
    pub normal_texture: Option<(Texture, f32)>,
    /// Alpha factor and alpha-test cutoff: rays pass through texels whose alpha (factor
    /// × the texture's, filtered as the GPU filters it, × the vertex colours') is below
    /// the cutoff.
    pub alpha: f32,
    pub cutoff: Option<f32>,
    /// Whether rays hit its back faces (single-sided: they pass through them).
    pub double_sided: bool,
}

impl SurfaceMaterial {
    /// `material` as the tracer reads it; textures whose texels do not match their size
    /// are left out, as if absent. `lowest_vertex_alpha` is the smallest vertex colour
    /// alpha of the meshes that use it (1 without vertex colours).
    fn new(material: &Material, lowest_vertex_alpha: f32) -> SurfaceMaterial {
        let usable =
            |t: &Texture| t.width > 0 && t.height > 0 && t.rgba8.len() as u64 == 4 * t.width as u64 * t.height as u64;
        // A material is alpha-tested where some texel or vertex can fall below its
        // cutoff (`Material::alpha_cutoff` with the vertex colours' alpha as well).
        let texture_alpha_min = material
            .diffuse_texture
            .as_ref()
            .map_or(255, |t| t.rgba8.chunks_exact(4).map(|c| c[3]).min().unwrap_or(255));
        let lowest = material.alpha * texture_alpha_min as f32 / 255.0 * lowest_vertex_alpha;
        SurfaceMaterial {
            diffuse: material.diffuse,
            emissive: material.emissive,
            texture: material.diffuse_texture.clone().filter(usable),
            emissive_texture: material.emissive_texture.clone().filter(usable),
            normal_texture: material.normal_texture.clone().filter(|(t, _)| usable(t)),
            alpha: material.alpha,
            cutoff: material.alpha_mode.cutoff().filter(|&cutoff| lowest < cutoff),
            double_sided: material.double_sided,
        }
    }

    /// Whether a ray passes through this material at texture coordinates `uvs` (sets 0
    /// and 1) with vertex colour alpha `vertex_alpha` (an alpha-tested hole).
    fn is_hole(&self, uvs: [Vec2; 2], vertex_alpha: f32) -> bool {
        let Some(cutoff) = self.cutoff else { return false };
        let alpha =
            self.alpha * vertex_alpha * self.texture.as_ref().map_or(1.0, |t| sample_alpha(t, t.sampling.pick(uvs)));
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
    /// Texture coordinates of sets 0 and 1 (each texture reads the one it names).
    pub uvs: [Vec2; 2],
    /// Interpolated linear RGBA vertex colour (white without vertex colours).
    pub color: Vec4,
    /// Barycentric weights of v1 and v2 (for the attributes looked up only when needed).
    pub b1: f32,
    pub b2: f32,
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
    /// Vertex colours and tangents of the triangles that have them.
    extras: Vec<TriExtras>,
    pub materials: Vec<SurfaceMaterial>,
    /// Whether some material is alpha-tested (rays then test each hit's alpha).
    has_holes: bool,
    /// Whether some material is single-sided (rays then pass through its back faces).
    has_single_sided: bool,
}

/// A scene's triangles as they are flattened, before the BVH puts them in leaf order.
struct Flattened {
    tris: Vec<Tri>,
    attributes: Vec<TriAttributes>,
    extras: Vec<TriExtras>,
}

impl Flattened {
    /// Adds `mesh`'s triangles relative to `anchor`, leaving out those with a non-finite
    /// vertex or no area; an index or material out of range is an input error.
    fn add_mesh(&mut self, mesh: &Mesh, materials: &[Material], anchor: DVec3) -> Result<()> {
        if mesh.material >= materials.len() {
            return Err(Error::input(format!(
                "mesh '{}' uses material {} of {}",
                mesh.name,
                mesh.material,
                materials.len()
            )));
        }
        let offset = mesh.origin - anchor;
        let count = mesh.positions.len();
        let has_normals = mesh.normals.len() == count;
        let has_uvs = mesh.uvs.len() == count;
        let has_colors = mesh.colors.len() == count;
        let has_uvs1 = mesh.uvs1.len() == count;
        let normal_mapped = materials[mesh.material].normal_texture.is_some();
        let has_tangents = normal_mapped && mesh.tangents.len() == count;
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
            self.tris.push(Tri { p: p.map(|v| v.to_array()) });
            let uv = |i: usize| if has_uvs { mesh.uvs[i] } else { Vec2::ZERO };
            let extra = if has_colors || has_tangents || has_uvs1 {
                self.extras.push(TriExtras {
                    colors: idx.map(|i| if has_colors { mesh.colors[i] } else { Vec4::ONE }),
                    tangents: idx.map(|i| if has_tangents { mesh.tangents[i] } else { Vec4::ZERO }),
                    uvs1: idx.map(|i| if has_uvs1 { mesh.uvs1[i] } else { uv(i) }),
                });
                (self.extras.len() - 1) as u32
            } else {
                NO_EXTRAS
            };
            self.attributes.push(TriAttributes {
                normals: idx.map(|i| if has_normals { mesh.normals[i] } else { Vec3::ZERO }),
                uvs: idx.map(uv),
                geometric: geometric / length,
                material: mesh.material as u32,
                extras: extra,
            });
        }
        Ok(())
    }
}

/// The BVH over `tris` (`None` without triangles), with `tris` and `attributes` put in
/// its leaf order so that a leaf's primitive id indexes them directly.
fn leaf_ordered_bvh(tris: &mut Vec<Tri>, attributes: &mut Vec<TriAttributes>) -> Option<CwBvh> {
    if tris.is_empty() {
        return None;
    }
    let boxes: Vec<Triangle> =
        tris.iter().map(|t| Triangle { v0: t.p[0].into(), v1: t.p[1].into(), v2: t.p[2].into() }).collect();
    let bvh =
        obvhs::cwbvh::builder::build_cwbvh_from_tris(&boxes, BvhBuildParams::medium_build(), &mut Duration::default());
    // Store the triangles in leaf order (without pre-splits this is a permutation).
    *tris = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
    *attributes = bvh.primitive_indices.iter().map(|&i| attributes[i as usize]).collect();
    Some(bvh)
}

impl SceneGeometry {
    /// Flattens `scene` relative to `anchor` and builds the BVH. Triangles with a
    /// non-finite vertex or no area are left out (they rasterise to nothing); an index or
    /// material out of range is an input error.
    pub(super) fn build(scene: &Scene, anchor: DVec3) -> Result<SceneGeometry> {
        // A scene that moves is traced frozen: callers pass `Scene::at_time` of the
        // frame's time; one that is not frozen is traced at time 0.
        let frozen;
        let scene = if scene.nodes.is_empty() {
            scene
        } else {
            frozen = scene.at_time(0.0);
            &frozen
        };
        let mut flat = Flattened {
            tris: Vec::with_capacity(scene.triangle_count()),
            attributes: Vec::with_capacity(scene.triangle_count()),
            extras: Vec::new(),
        };
        for mesh in &scene.meshes {
            flat.add_mesh(mesh, &scene.materials, anchor)?;
        }
        let Flattened { mut tris, mut attributes, extras } = flat;
        let bvh = leaf_ordered_bvh(&mut tris, &mut attributes);
        let materials: Vec<SurfaceMaterial> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| SurfaceMaterial::new(m, lowest_vertex_alpha(&scene.meshes, i)))
            .collect();
        let has_holes = materials.iter().any(|m| m.cutoff.is_some());
        let has_single_sided = materials.iter().any(|m| !m.double_sided);
        Ok(SceneGeometry { bvh, tris, attributes, extras, materials, has_holes, has_single_sided })
    }

    #[cfg(test)]
    pub(super) fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The uvs of sets 0 and 1 at barycentrics (b1, b2) of leaf-order triangle `prim`.
    fn uvs_at(&self, prim: usize, b1: f32, b2: f32) -> [Vec2; 2] {
        let a = &self.attributes[prim];
        let at = |uvs: &[Vec2; 3]| uvs[0] * (1.0 - b1 - b2) + uvs[1] * b1 + uvs[2] * b2;
        let uv0 = at(&a.uvs);
        match a.extras {
            NO_EXTRAS => [uv0, uv0],
            i => [uv0, at(&self.extras[i as usize].uvs1)],
        }
    }

    /// The interpolated vertex colour at barycentrics (b1, b2) of leaf-order triangle
    /// `prim` (white without vertex colours).
    fn color_at(&self, prim: usize, b1: f32, b2: f32) -> Vec4 {
        match self.attributes[prim].extras {
            NO_EXTRAS => Vec4::ONE,
            i => {
                let c = &self.extras[i as usize].colors;
                c[0] * (1.0 - b1 - b2) + c[1] * b1 + c[2] * b2
            }
        }
    }

    /// The closest hit with t in (`tmin`, `tmax`) along unit `dir` from `origin`, ignoring
    /// triangle `skip` (`u32::MAX` for none) and alpha-tested holes.
    pub(super) fn closest(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32, skip: u32) -> Option<Hit> {
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
                Some(_) if self.has_single_sided && self.is_behind(id, dir) => f32::INFINITY,
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
        material.cutoff.is_some() && material.is_hole(self.uvs_at(prim, b1, b2), self.color_at(prim, b1, b2).w)
    }

    /// Whether a ray along `dir` meets `prim` from behind and its material is single-sided
    /// (culled, as the raster passes cull it: counter-clockwise is the front).
    fn is_behind(&self, prim: usize, dir: Vec3) -> bool {
        let a = &self.attributes[prim];
        !self.materials[a.material as usize].double_sided && a.geometric.dot(dir) >= 0.0
    }

    /// The attributes at `hit`.
    pub(super) fn surface(&self, hit: &Hit) -> Surface {
        let tri = &self.tris[hit.prim as usize];
        let a = &self.attributes[hit.prim as usize];
        let [p0, p1, p2] = tri.p.map(Vec3::from);
        let (b1, b2) = (hit.b1, hit.b2);
        let b0 = 1.0 - b1 - b2;
        let position = p0 + (p1 - p0) * b1 + (p2 - p0) * b2;
        let n = a.normals[0] * b0 + a.normals[1] * b1 + a.normals[2] * b2;
        let shading = n.try_normalize().unwrap_or(a.geometric);
        let magnitude = p0.abs().max(p1.abs()).max(p2.abs()).max_element();
        Surface {
            prim: hit.prim,
            position,
            geometric: a.geometric,
            shading,
            uvs: self.uvs_at(hit.prim as usize, b1, b2),
            color: self.color_at(hit.prim as usize, b1, b2),
            b1,
            b2,
            material: a.material as usize,
            magnitude,
        }
    }

    /// The normal that lights `surface`: its material's normal texture applied in the
    /// frame of the interpolated vertex normal and tangent (glTF's convention: n =
    /// normalize(T·x + B·y + N·z) with (x, y, z) = 2·texel − 1, x and y times the scale,
    /// B = (N × T)·w), or the interpolated vertex normal without a normal texture, without
    /// tangents or where the frame degenerates. Only the direct light of a bounce's sender
    /// reads it (as the direct pass lights the G-buffer's normal-mapped normal); the
    /// occlusion and the environment stay on the vertex normal.
    pub(super) fn lighting_normal(&self, surface: &Surface) -> Vec3 {
        let n = surface.shading;
        let Some((texture, scale)) = &self.materials[surface.material].normal_texture else { return n };
        let a = &self.attributes[surface.prim as usize];
        if a.extras == NO_EXTRAS {
            return n;
        }
        let t = &self.extras[a.extras as usize].tangents;
        let (b1, b2) = (surface.b1, surface.b2);
        let tangent = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
        let Some(tangent) = (tangent.truncate() - n * n.dot(tangent.truncate())).try_normalize() else { return n };
        let sign = if tangent_sign(t, b1, b2) < 0.0 { -1.0 } else { 1.0 };
        let bitangent = n.cross(tangent) * sign;
        let texel = sample_linear(texture, texture.sampling.pick(surface.uvs)) * 2.0 - Vec3::ONE;
        let (x, y) = (texel.x * scale, texel.y * scale);
        (tangent * x + bitangent * y + n * texel.z).try_normalize().unwrap_or(n)
    }
}

/// The bitangent sign at (b1, b2) of a triangle's tangents: interpolated, as the G-buffer
/// receives it.
fn tangent_sign(t: &[Vec4; 3], b1: f32, b2: f32) -> f32 {
    t[0].w * (1.0 - b1 - b2) + t[1].w * b1 + t[2].w * b2
}

/// The smallest vertex colour alpha over the meshes that use material `material` (1 where
/// none has vertex colours).
fn lowest_vertex_alpha(meshes: &[Mesh], material: usize) -> f32 {
    meshes
        .iter()
        .filter(|m| m.material == material && m.colors.len() == m.positions.len())
        .flat_map(|m| m.colors.iter().map(|c| c.w))
        .fold(1.0, f32::min)
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

/// Texel coordinates beyond this (in texels) are held there: f32 coordinates that large
/// have no fraction left, and the integer arithmetic after them stays far from overflow.
const TEXEL_LIMIT: f64 = (1u64 << 40) as f64;

/// `texture` at `uv` as its [`Sampling`] says: `uv` moved by the transform, then wrapped
/// per axis and filtered with the magnification filter, at the full-size level (see the
/// module docs); v = 0 is the top row ([`vrao_render::scene::Mesh::uvs`]). `texel` reads
/// the texel at a byte offset into `rgba8`; `lerp` blends two of them.
fn filtered<T: Copy>(texture: &Texture, uv: Vec2, texel: impl Fn(usize) -> T, lerp: impl Fn(T, T, f32) -> T) -> T {
    let Sampling { wrap_u, wrap_v, magnify, .. } = texture.sampling;
    let (w, h) = (texture.width as i64, texture.height as i64);
    let placed = texture.sampling.place(uv);
    let uv = if placed.is_finite() { placed } else { Vec2::ZERO };
    let x = (uv.x as f64 * w as f64).clamp(-TEXEL_LIMIT, TEXEL_LIMIT);
    let y = (uv.y as f64 * h as f64).clamp(-TEXEL_LIMIT, TEXEL_LIMIT);
    let at = |x: i64, y: i64| texel(4 * (wrap_v.texel(y, h) * w + wrap_u.texel(x, w)) as usize);
    match magnify {
        Filter::Nearest => at(x.floor() as i64, y.floor() as i64),
        Filter::Linear => {
            let (x, y) = (x - 0.5, y - 0.5);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let top = lerp(at(x0, y0), at(x0 + 1, y0), fx);
            let bottom = lerp(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx);
            lerp(top, bottom, fy)
        }
    }
}

/// Lookup of an sRGB texture's colour (decoded to linear before filtering, as an sRGB
/// texture format does), as [`filtered`] says.
pub(crate) fn sample_texture(texture: &Texture, uv: Vec2) -> Vec3 {
    let texel = |i: usize| {
        let b = &texture.rgba8[i..i + 3];
        Vec3::new(srgb_to_linear(b[0]), srgb_to_linear(b[1]), srgb_to_linear(b[2]))
    };
    filtered(texture, uv, texel, Vec3::lerp)
}

/// Lookup of a linear texture's colour (a normal texture: bytes / 255, filtered as they
/// are), as [`filtered`] says.
pub(crate) fn sample_linear(texture: &Texture, uv: Vec2) -> Vec3 {
    let texel = |i: usize| {
        let b = &texture.rgba8[i..i + 3];
        Vec3::new(b[0] as f32, b[1] as f32, b[2] as f32) / 255.0
    };
    filtered(texture, uv, texel, Vec3::lerp)
}

/// Lookup of a texture's alpha (linear bytes, as the GPU filters them), as [`filtered`] says.
pub(crate) fn sample_alpha(texture: &Texture, uv: Vec2) -> f32 {
    let texel = |i: usize| texture.rgba8[i + 3] as f32 / 255.0;
    filtered(texture, uv, texel, |a, b, t| a + (b - a) * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vrao_ao::HeadPose;
    use vrao_render::scene::{HeadPath, Material, Mesh};

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
                uvs1: Vec::new(),
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
        let t = Texture { sampling: Default::default(), width: 2, height: 2, rgba8: rgba8.into(), source: None };
        assert_eq!(sample_texture(&t, Vec2::new(0.25, 0.25)), Vec3::ZERO);
        assert_eq!(sample_texture(&t, Vec2::new(0.75, 0.25)), Vec3::ONE);
        assert_eq!(sample_texture(&t, Vec2::new(0.25, 0.75)), Vec3::X);
        // Halfway between the top texels; wrapping in u at the left edge.
        assert!((sample_texture(&t, Vec2::new(0.5, 0.25)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert!((sample_texture(&t, Vec2::new(0.0, 0.25)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert!(sample_texture(&t, Vec2::new(f32::NAN, 7.0)).is_finite());
    }
}

#[cfg(test)]
mod sampling_tests {
    //! Texture lookups as the GPU's sampler makes them: wrap per axis, nearest or linear,
    //! the texture transform first.
    use super::*;
    use glam::Affine2;
    use vrao_render::scene::texture::uv_transform;
    use vrao_render::scene::Wrap;

    /// A 2×2 texture whose texel (x, y) has alpha (10 + 10x + 20y) / 255 (10, 20 on the
    /// top row, 30, 40 below), sampled as `sampling` says.
    fn two_by_two(sampling: Sampling) -> Texture {
        let rgba8 = [10u8, 20, 30, 40].iter().flat_map(|&a| [a, a, a, a]).collect::<Vec<u8>>().into();
        Texture { width: 2, height: 2, rgba8, source: None, sampling }
    }

    /// The texel (x, y) of [`two_by_two`] that an alpha value names.
    fn texel_of(alpha: f32) -> (i64, i64) {
        let a = (alpha * 255.0).round() as i64;
        assert!([10, 20, 30, 40].contains(&a), "alpha {a} is a blend, not one texel");
        ((a / 10 - 1) % 2, (a / 10 - 1) / 2)
    }

    fn nearest(wrap_u: Wrap, wrap_v: Wrap) -> Sampling {
        Sampling { wrap_u, wrap_v, magnify: Filter::Nearest, ..Sampling::default() }
    }

    #[test]
    fn each_wrap_mode_addresses_texels_outside_the_unit_square_on_each_axis() {
        // Coordinate → texel column of a 2-texel row, for repeat, mirrored repeat, clamp.
        let cases: [(f32, [i64; 3]); 8] = [
            (-1.25, [1, 1, 0]),
            (-0.75, [0, 1, 0]),
            (-0.25, [1, 0, 0]),
            (0.25, [0, 0, 0]),
            (1.25, [0, 1, 1]),
            (1.75, [1, 0, 1]),
            (2.25, [0, 0, 1]),
            (3.75, [1, 0, 1]),
        ];
        let modes = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge];
        for (c, expected) in cases {
            for (mode, want) in modes.into_iter().zip(expected) {
                // The other axis is inside the texture, its mode one that differs.
                let other = if mode == Wrap::ClampToEdge { Wrap::Repeat } else { Wrap::ClampToEdge };
                let along_u = two_by_two(nearest(mode, other));
                assert_eq!(texel_of(sample_alpha(&along_u, Vec2::new(c, 0.25))), (want, 0), "u = {c}, {mode:?}");
                let along_v = two_by_two(nearest(other, mode));
                assert_eq!(texel_of(sample_alpha(&along_v, Vec2::new(0.25, c))), (0, want), "v = {c}, {mode:?}");
            }
        }
        // Both axes at once, each with its own mode (the floor: v clamped while u
        // repeated drew one stripe down where glTF's default repeats both).
        let t = two_by_two(nearest(Wrap::Repeat, Wrap::MirroredRepeat));
        assert_eq!(texel_of(sample_alpha(&t, Vec2::new(1.25, 1.25))), (0, 1));
        assert_eq!(texel_of(sample_alpha(&t, Vec2::new(-0.25, 2.75))), (1, 1));
        let default = two_by_two(Sampling { magnify: Filter::Nearest, ..Sampling::default() });
        for k in -3..4 {
            let (u, v) = (k as f32 + 0.25, k as f32 + 0.75);
            assert_eq!(texel_of(sample_alpha(&default, Vec2::new(u, v))), (0, 1), "repeat both at ({u}, {v})");
        }
    }

    #[test]
    fn linear_filtering_blends_across_the_wrapped_edge_and_nearest_does_not() {
        let alpha = |s: Sampling, u: f32, v: f32| sample_alpha(&two_by_two(s), Vec2::new(u, v)) * 255.0;
        let linear = |wrap_u, wrap_v| Sampling { wrap_u, wrap_v, ..Sampling::default() };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-3;
        // Between the two top texels: linear blends them, nearest takes the right one.
        assert!(close(alpha(linear(Wrap::Repeat, Wrap::Repeat), 0.5, 0.25), 15.0));
        assert!(close(alpha(nearest(Wrap::Repeat, Wrap::Repeat), 0.5, 0.25), 20.0));
        assert!(close(alpha(nearest(Wrap::Repeat, Wrap::Repeat), 0.49, 0.25), 10.0));
        // At u = 1 the bilinear footprint straddles the edge: repeat blends the last
        // column with the first, mirrored repeat and clamp with itself.
        assert!(close(alpha(linear(Wrap::Repeat, Wrap::Repeat), 1.0, 0.25), 15.0));
        assert!(close(alpha(linear(Wrap::MirroredRepeat, Wrap::Repeat), 1.0, 0.25), 20.0));
        assert!(close(alpha(linear(Wrap::ClampToEdge, Wrap::Repeat), 1.0, 0.25), 20.0));
        // The same down v: repeat blends the bottom row with the top one.
        assert!(close(alpha(linear(Wrap::ClampToEdge, Wrap::Repeat), 0.25, 1.0), 20.0));
        assert!(close(alpha(linear(Wrap::ClampToEdge, Wrap::ClampToEdge), 0.25, 1.0), 30.0));
        // A quarter texel in from the centre of texel (0, 0) towards (1, 1).
        let c = alpha(linear(Wrap::Repeat, Wrap::Repeat), 0.375, 0.375);
        assert!(close(c, 10.0 + 0.25 * 10.0 + 0.25 * 20.0), "{c}");
        // Colour is decoded from sRGB before it is blended, as an sRGB format does.
        let mut t = two_by_two(Sampling::default());
        t.rgba8 = [0u8, 255, 0, 255].iter().flat_map(|&c| [c, c, c, 255]).collect::<Vec<u8>>().into();
        assert!((sample_texture(&t, Vec2::new(0.5, 0.25)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        t.sampling.magnify = Filter::Nearest;
        assert_eq!(sample_texture(&t, Vec2::new(0.5, 0.25)), Vec3::ONE);
    }

    #[test]
    fn the_texture_transform_moves_uvs_before_they_wrap() {
        let with = |transform: Affine2| two_by_two(Sampling { transform, ..nearest(Wrap::Repeat, Wrap::Repeat) });
        let at = |t: &Texture, u: f32, v: f32| texel_of(sample_alpha(t, Vec2::new(u, v)));
        // Offset by half the texture in u: texel (0, 0)'s uvs read texel (1, 0).
        let offset = with(uv_transform(Vec2::new(0.5, 0.0), 0.0, Vec2::ONE));
        assert_eq!(at(&offset, 0.25, 0.25), (1, 0));
        assert_eq!(at(&offset, 0.75, 0.25), (0, 0), "and wraps");
        // Scaled by 2: the texture repeats twice across the unit square.
        let scaled = with(uv_transform(Vec2::ZERO, 0.0, Vec2::splat(2.0)));
        assert_eq!(at(&scaled, 0.3, 0.3), (1, 1));
        assert_eq!(at(&scaled, 0.55, 0.8), (0, 1));
        // Rotated a quarter turn: (u, v) is read at (v, −u).
        let rotated = with(uv_transform(Vec2::ZERO, std::f32::consts::FRAC_PI_2, Vec2::ONE));
        assert_eq!(rotated.sampling.place(Vec2::new(0.25, 0.75)).round(), Vec2::new(1.0, 0.0));
        assert_eq!(at(&rotated, 0.25, 0.75), (1, 1));
        assert_eq!(at(&rotated, 0.75, 0.25), (0, 0));
        // All three: translation · rotation · scale, applied in that order to the uv.
        let all = with(uv_transform(Vec2::new(0.5, 0.5), std::f32::consts::PI, Vec2::splat(0.5)));
        let placed = all.sampling.place(Vec2::new(0.2, 0.6));
        assert!((placed - Vec2::new(0.4, 0.2)).length() < 1e-6, "{placed}");
        assert_eq!(at(&all, 0.2, 0.6), (0, 0));
        // A transform that sends uvs to infinity reads a texel, never out of bounds.
        let huge = with(Affine2::from_scale(Vec2::splat(f32::MAX)));
        assert!(sample_alpha(&huge, Vec2::new(3.0, -7.0)).is_finite());
        let far = two_by_two(Sampling::default());
        assert!(sample_alpha(&far, Vec2::new(1e30, -3e38)).is_finite());
    }
}
