//! Vertex normals for meshes that come without them (all three shared scenes do).
//!
//! Normals are smooth and area-weighted (the sum of unnormalised face cross products), but
//! only across faces that meet at less than a crease angle: where faces meet more sharply
//! the vertex is split, so boxes and architecture stay flat-shaded while a scanned surface
//! such as the bunny is smooth. Faces are joined by position, not by vertex index, so a
//! texture seam does not become a shading seam. No output normal is ever NaN.

use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Faces meeting at more than this angle (degrees) get separate vertex normals.
pub const DEFAULT_CREASE_DEG: f32 = 60.0;

/// Vertex arrays and a triangle list, as the normal computation reads and writes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    /// Vertex positions (m).
    pub positions: Vec<Vec3>,
    /// Vertex normals, one per position (unit length once computed).
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty.
    pub uvs: Vec<Vec2>,
    /// Triangle list: three indices into `positions` per face.
    pub indices: Vec<u32>,
}

/// The normal used where nothing defines one (a vertex touched only by degenerate faces).
const FALLBACK_NORMAL: Vec3 = Vec3::Y;

/// The triangles of `indices` whose three indices are in range, with their unnormalised
/// normals (twice the area along the CCW normal). Out-of-range triangles cannot be drawn,
/// so they are dropped; a trailing partial triangle likewise.
fn triangles(positions: &[Vec3], indices: &[u32]) -> Vec<([u32; 3], Vec3)> {
    indices
        .chunks_exact(3)
        .filter(|t| t.iter().all(|&i| (i as usize) < positions.len()))
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            ([t[0], t[1], t[2]], (b - a).cross(c - a))
        })
        .collect()
}

/// Smooth, area-weighted vertex normals that stay sharp across creases steeper than
/// `crease_angle_deg`. `uvs` is either empty or one per position; the result has one
/// position, normal and uv per output vertex (vertices are duplicated where a crease
/// splits them). Zero-area triangles are kept in the index list but carry no weight.
pub fn compute_normals(positions: &[Vec3], uvs: &[Vec2], indices: &[u32], crease_angle_deg: f32) -> Geometry {
    compute_normals_with_sources(positions, uvs, indices, crease_angle_deg).0
}

/// [`compute_normals`], with the input vertex each output vertex was made from (so that
/// further per-vertex data, such as colours, can follow the split).
pub fn compute_normals_with_sources(
    positions: &[Vec3],
    uvs: &[Vec2],
    indices: &[u32],
    crease_angle_deg: f32,
) -> (Geometry, Vec<u32>) {
    let crease = if crease_angle_deg.is_finite() { crease_angle_deg } else { DEFAULT_CREASE_DEG };
    let cos_crease = crease.clamp(0.0, 180.0).to_radians().cos();
    let tris = triangles(positions, indices);
    let units: Vec<Option<Vec3>> = tris.iter().map(|(_, n)| n.try_normalize()).collect();
    let fans = Fans::new(positions, &tris);
    let mut corners = CornerNormals {
        tris: &tris,
        units: &units,
        fans: &fans,
        cos_crease,
        around_of: HashMap::new(),
        memo: HashMap::new(),
    };
    split_vertices(positions, uvs, &tris, |f, v| corners.normal(f, fans.weld[v as usize]))
}

/// Input vertices welded by position, and the faces around each welded vertex: faces
/// are joined by position, so a texture seam does not become a shading seam.
struct Fans {
    /// The welded vertex of each input vertex.
    weld: Vec<usize>,
    /// Where each welded vertex's faces begin in `faces` (compressed-row form; one more
    /// entry than welded vertices).
    start: Vec<usize>,
    /// The faces around each welded vertex, one run per vertex.
    faces: Vec<usize>,
}

impl Fans {
    fn new(positions: &[Vec3], tris: &[([u32; 3], Vec3)]) -> Fans {
        // Weld vertices by exact position (adding 0.0 turns -0.0 into +0.0 so both weld).
        let mut weld_of_position: HashMap<[u32; 3], usize> = HashMap::new();
        let weld: Vec<usize> = positions
            .iter()
            .map(|p| {
                let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
                let next = weld_of_position.len();
                *weld_of_position.entry(key).or_insert(next)
            })
            .collect();

        // Faces around each welded vertex, in compressed-row form.
        let mut start = vec![0usize; weld_of_position.len() + 1];
        for (corners, _) in tris {
            for &v in corners {
                start[weld[v as usize] + 1] += 1;
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut fill = start.clone();
        let mut faces = vec![0usize; start[start.len() - 1]];
        for (f, (corners, _)) in tris.iter().enumerate() {
            for &v in corners {
                let w = weld[v as usize];
                faces[fill[w]] = f;
                fill[w] += 1;
            }
        }
        Fans { weld, start, faces }
    }

    /// The faces around welded vertex `w`.
    fn around(&self, w: usize) -> &[usize] {
        &self.faces[self.start[w]..self.start[w + 1]]
    }
}

/// Around a vertex of many faces (a fan's centre, a sphere's pole, or a 1 MB file that
/// repeats one triangle 100,000 times) summing every face per corner would cost faces²
/// (hours). There a corner's normal depends only on the vertex and its face's unit
/// normal, so it is found once per pair, from the faces summed by their unit normal: the
/// same result up to the order of the additions. A vertex whose faces point in more than
/// `MANY` directions is smoothed over all of them (no crease split there).
const MANY: usize = 64;

/// The faces around a vertex of many faces, summed by unit normal.
enum Around {
    /// Each distinct unit normal and the sum of its faces' weighted normals.
    Directions(Vec<(Vec3, Vec3)>),
    /// More than `MANY` directions: all faces' weighted normals summed.
    Smooth(Vec3),
}

impl Around {
    /// The faces of `around` (indices into `tris` and `units`) grouped by unit normal;
    /// degenerate faces carry no weight and are left out.
    fn sum(around: &[usize], tris: &[([u32; 3], Vec3)], units: &[Option<Vec3>]) -> Around {
        let mut directions: Vec<(Vec3, Vec3)> = Vec::new();
        let mut index_of: HashMap<[u32; 3], usize> = HashMap::new();
        for &g in around {
            let Some(unit) = units[g] else { continue };
            let next = directions.len();
            let i = *index_of.entry(unit.to_array().map(f32::to_bits)).or_insert(next);
            if i == next {
                directions.push((unit, Vec3::ZERO));
            }
            directions[i].1 += tris[g].1;
        }
        if directions.len() > MANY {
            Around::Smooth(directions.iter().map(|d| d.1).sum())
        } else {
            Around::Directions(directions)
        }
    }
}

/// Each face corner's normal: the weighted sum over the faces around its welded vertex
/// within the crease angle of the corner's face.
struct CornerNormals<'a> {
    /// The triangles and their unnormalised normals.
    tris: &'a [([u32; 3], Vec3)],
    /// Each triangle's unit normal, `None` for a degenerate one.
    units: &'a [Option<Vec3>],
    fans: &'a Fans,
    cos_crease: f32,
    /// Vertices of many faces, their faces summed by direction (see [`MANY`]).
    around_of: HashMap<usize, Around>,
    /// Normals found at vertices of many faces, by vertex and face unit normal.
    memo: HashMap<(usize, Option<[u32; 3]>), Vec3>,
}

impl CornerNormals<'_> {
    /// Face `f`'s unit normal, or for a degenerate face the largest face's of `around`.
    fn own_normal(&self, f: usize, around: &[usize]) -> Option<Vec3> {
        self.units[f].or_else(|| {
            let largest = around
                .iter()
                .copied()
                .max_by(|&a, &b| self.tris[a].1.length_squared().total_cmp(&self.tris[b].1.length_squared()))?;
            self.units[largest]
        })
    }

    /// The normal of face `f`'s corner at welded vertex `w`.
    fn normal(&mut self, f: usize, w: usize) -> Vec3 {
        if self.fans.around(w).len() <= MANY {
            return self.summed_directly(f, w);
        }
        let key = (w, self.units[f].map(|u| u.to_array().map(f32::to_bits)));
        if let Some(&normal) = self.memo.get(&key) {
            return normal;
        }
        let normal = self.summed_by_direction(f, w);
        self.memo.insert(key, normal);
        normal
    }

    /// The corner normal from every face around `w` (a vertex of few faces).
    fn summed_directly(&self, f: usize, w: usize) -> Vec3 {
        let around = self.fans.around(w);
        let own = self.own_normal(f, around);
        let Some(own) = own else { return FALLBACK_NORMAL };
        let sum: Vec3 = around
            .iter()
            .filter(|&&g| self.units[g].is_some_and(|u| u.dot(own) >= self.cos_crease))
            .map(|&g| self.tris[g].1)
            .sum();
        sum.try_normalize().unwrap_or(own)
    }

    /// The corner normal from the faces around `w` summed by direction (a vertex of many).
    fn summed_by_direction(&mut self, f: usize, w: usize) -> Vec3 {
        let around = self.fans.around(w);
        let Some(own) = self.own_normal(f, around) else { return FALLBACK_NORMAL };
        let (tris, units) = (self.tris, self.units);
        let summed = self.around_of.entry(w).or_insert_with(|| Around::sum(around, tris, units));
        let sum: Vec3 = match summed {
            Around::Directions(directions) => {
                directions.iter().filter(|(u, _)| u.dot(own) >= self.cos_crease).map(|d| d.1).sum()
            }
            Around::Smooth(sum) => *sum,
        };
        sum.try_normalize().unwrap_or(own)
    }
}

/// One output vertex per (input vertex, normal): corners that agree share a vertex.
/// `normal(f, v)` is face `f`'s normal at its corner on input vertex `v`. Returns the
/// geometry and each output vertex's input vertex.
fn split_vertices(
    positions: &[Vec3],
    uvs: &[Vec2],
    tris: &[([u32; 3], Vec3)],
    mut normal: impl FnMut(usize, u32) -> Vec3,
) -> (Geometry, Vec<u32>) {
    let mut out = Geometry::default();
    let mut sources = Vec::new();
    let mut output_of: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    for (f, (corners, _)) in tris.iter().enumerate() {
        for &v in corners {
            let normal = normal(f, v);
            let key = (v, normal.to_array().map(f32::to_bits));
            let index = *output_of.entry(key).or_insert_with(|| {
                out.positions.push(positions[v as usize]);
                out.normals.push(normal);
                out.uvs.push(uvs.get(v as usize).copied().unwrap_or(Vec2::ZERO));
                sources.push(v);
                (out.positions.len() - 1) as u32
            });
            out.indices.push(index);
        }
    }
    (out, sources)
}

/// Makes normals read from a file unit length. A zero-length or non-finite normal is
/// replaced by the area-weighted normal of the faces around its vertex (the face normal
/// when there is one face), or +Y when those faces have no area either.
pub fn repair_normals(positions: &[Vec3], normals: &mut [Vec3], indices: &[u32]) {
    let mut face_sums: Option<Vec<Vec3>> = None;
    for (v, normal) in normals.iter_mut().enumerate() {
        if let Some(unit) = normal.try_normalize() {
            *normal = unit;
            continue;
        }
        let sums = face_sums.get_or_insert_with(|| {
            let mut sums = vec![Vec3::ZERO; positions.len()];
            for (corners, n) in triangles(positions, indices) {
                corners.iter().for_each(|&c| sums[c as usize] += n);
            }
            sums
        });
        *normal = sums.get(v).and_then(|s| s.try_normalize()).unwrap_or(FALLBACK_NORMAL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(positions: &[Vec3], indices: &[u32]) -> Geometry {
        compute_normals(positions, &[], indices, DEFAULT_CREASE_DEG)
    }

    /// A unit cube with 8 shared corners and CCW-outward faces.
    fn cube() -> (Vec<Vec3>, Vec<u32>) {
        let p = (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32)).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let indices = quads.iter().flat_map(|q: &[u32; 4]| [q[0], q[1], q[2], q[0], q[2], q[3]]).collect();
        (p, indices)
    }

    #[test]
    fn a_vertex_of_many_faces_costs_no_more_than_its_faces() {
        // One triangle repeated 200,000 times (a 1.6 MB OBJ) took hours: every corner
        // summed every face around its vertex.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let indices: Vec<u32> = (0..600_000).map(|i| i % 3).collect();
        let started = std::time::Instant::now();
        let g = geometry(&p, &indices);
        assert!(started.elapsed().as_secs() < 5, "{:?}", started.elapsed());
        assert_eq!(g.positions.len(), 3);
        assert!(g.normals.iter().all(|n| *n == Vec3::Z));
        // A cone of 1000 faces: at its apex, where they point in 1000 directions, the
        // normal is the smooth one (+Y), found once.
        let mut p = vec![Vec3::Y];
        p.extend((0..1000).map(|i| {
            let a = std::f32::consts::TAU * i as f32 / 1000.0;
            Vec3::new(a.cos(), 0.0, -a.sin())
        }));
        let fan: Vec<u32> = (0..1000u32).flat_map(|i| [0, 1 + i, 1 + (i + 1) % 1000]).collect();
        let g = geometry(&p, &fan);
        let apex = g.indices.chunks(3).map(|t| g.normals[t[0] as usize]).collect::<Vec<_>>();
        assert!(apex.iter().all(|n| n.is_finite() && n.dot(Vec3::Y) > 0.99), "{:?}", apex[0]);
    }

    #[test]
    fn cube_stays_flat_shaded() {
        let (p, i) = cube();
        let g = geometry(&p, &i);
        assert_eq!(g.indices.len(), 36);
        assert_eq!(g.positions.len(), 24, "each corner splits into three face vertices");
        let centre = Vec3::splat(0.5);
        for t in g.indices.chunks(3) {
            let n = g.normals[t[0] as usize];
            assert!(t.iter().all(|&v| g.normals[v as usize] == n), "one normal per face");
            assert_eq!(n.abs().max_element(), 1.0, "axis-aligned: {n}");
            assert!(n.dot(g.positions[t[0] as usize] - centre) > 0.0, "outward");
        }
    }

    #[test]
    fn fine_sphere_normals_are_radial_within_one_degree() {
        let (rings, segments) = (90, 180);
        // Rings of vertices from pole to pole; each pole row is one point repeated (the
        // points weld by position), and the seam wraps around by index.
        let mut p = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let dir = match r {
                    0 => Vec3::Y,
                    r if r == rings => Vec3::NEG_Y,
                    _ => Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()),
                };
                p.push(dir * 3.0);
            }
        }
        let mut i = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let [a, b] = [s, (s + 1) % segments].map(|s| (r * segments + s) as u32);
                let row = segments as u32;
                i.extend([a, a + row, b + row, a, b + row, b]);
            }
        }
        let g = geometry(&p, &i);
        let cos_one_degree = 1f32.to_radians().cos();
        for (n, q) in g.normals.iter().zip(&g.positions) {
            assert!(n.dot(q.normalize()) > cos_one_degree, "normal {n} at {q}");
        }
    }

    #[test]
    fn larger_face_weighs_more() {
        // A big and a tiny triangle share vertex 0 and meet at a shallow angle.
        let p = [
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -4.0),
            Vec3::new(-0.1, 0.0, 0.0),
            Vec3::new(0.0, 0.02, 0.1),
        ];
        let g = geometry(&p, &[0, 1, 2, 0, 3, 4]);
        let big = Vec3::Y;
        let small = (p[3] - p[0]).cross(p[4] - p[0]).normalize();
        assert!(small.dot(big) > 30f32.to_radians().cos(), "the test needs a shallow angle");
        let shared = g.normals[g.indices[0] as usize];
        assert_eq!(shared, g.normals[g.indices[3] as usize], "smoothed into one vertex");
        // An unweighted mean would sit halfway (about 5.7° from each face).
        assert!(shared.dot(big) > 0.5f32.to_radians().cos(), "{shared} follows the big face");
    }

    #[test]
    fn degenerate_triangles_give_no_nan() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::ZERO, Vec3::ZERO];
        // Collinear, repeated-vertex and coincident triangles, plus an out-of-range one.
        let g = geometry(&p, &[0, 1, 2, 0, 0, 1, 3, 4, 0, 0, 1, 99]);
        assert_eq!(g.indices.len(), 9, "degenerate triangles stay, out-of-range ones go");
        assert!(g.normals.iter().all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-6));
        let mixed = geometry(&[Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::X * 2.0], &[0, 2, 1, 0, 1, 3]);
        assert!(mixed.normals.iter().all(|n| *n == Vec3::Y), "the collinear face borrows its neighbour's normal");
    }

    #[test]
    fn uvs_travel_with_split_vertices() {
        let (p, i) = cube();
        let uvs: Vec<Vec2> = (0..8).map(|v| Vec2::new(v as f32, 0.0)).collect();
        let g = compute_normals(&p, &uvs, &i, DEFAULT_CREASE_DEG);
        for (q, uv) in g.positions.iter().zip(&g.uvs) {
            assert_eq!(p[uv.x as usize], *q);
        }
    }

    #[test]
    fn bad_file_normals_are_repaired() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::NEG_Z, Vec3::Y];
        let mut n = [Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NAN, Vec3::ZERO];
        repair_normals(&p, &mut n, &[0, 1, 2]);
        assert_eq!(n, [Vec3::Y, Vec3::Y, Vec3::Y, Vec3::Y]);
    }
}
