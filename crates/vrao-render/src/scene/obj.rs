//! Wavefront OBJ + MTL loading.
//!
//! tobj parses the geometry, but its errors carry no line numbers and some bad input
//! passes silently, so the OBJ text is first checked line by line here: every number must
//! be finite and every face index must name an element defined above it. tobj then reads
//! a cleaned copy (comments, vertex colours, lines, points and unknown statements removed),
//! so it only ever sees what was checked.
//!
//! Material libraries are parsed here rather than by tobj: the checks need the lines
//! anyway, and tobj 4.0.5 panics on a colour with fewer than three numbers (`Kd 0.5`,
//! which the MTL spec allows). tobj still assigns each mesh its material, from the names
//! this module hands it through its material loader.
//!
//! Alpha: `d` (or `Tr` = 1 − d) is the material's alpha factor; `map_d` is an alpha map
//! (its alpha channel, or its grey level when it has none) merged into the diffuse
//! texture's alpha (a white texture when there is no `map_Kd`; resampled by nearest texel
//! when the sizes differ) and alpha-tested at 0.5 ([`super::AlphaMode::Mask`]); `d` < 1
//! without `map_d` is [`super::AlphaMode::Blend`].
//!
//! Conventions: texture v is flipped so that v = 0 is the top row of the image. Missing
//! normals are computed with [`normals::DEFAULT_CREASE_DEG`] creases. Zero-area triangles
//! are kept (they rasterise to nothing and keep triangle counts equal to the file's) but
//! carry no weight in normals.

use super::limits::GeometryBudget;
use super::normals::{self, Geometry};
use super::{Environment, HeadPath, Light, Material, Mesh, Scene, Texture};
use glam::{DVec3, Vec2, Vec3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use vrao_ao::{Error, Result};

/// Diffuse reflectance when a material gives no `Kd`, and of the material given to meshes
/// without one.
pub const DEFAULT_DIFFUSE: f32 = 0.8;

/// Loads the meshes of an OBJ file and the materials of its MTL libraries. Mesh material
/// indices start at `material_offset`, so the materials can be appended to a scene that
/// already holds that many. A grey material is appended when some mesh names none (or
/// names one no library defines). A missing library is a warning, not an error.
pub fn load_obj(path: &Path, material_offset: usize) -> Result<(Vec<Mesh>, Vec<Material>)> {
    load_obj_within(path, material_offset, GeometryBudget::default())
}

/// [`load_obj`] for a scene that already holds `used` triangles and vertices: the file is
/// refused at the face (or vertex) that passes the scene's budget ([`super::limits`]),
/// before the meshes are built.
pub fn load_obj_within(
    path: &Path,
    material_offset: usize,
    used: GeometryBudget,
) -> Result<(Vec<Mesh>, Vec<Material>)> {
    let text = read_text(path)?;
    let scan = scan_obj(path, &text, used)?;
    let mut libraries: HashMap<PathBuf, Vec<MtlMaterial>> = HashMap::new();
    for (library, line) in &scan.libraries {
        match crate::files::check_regular_file(library) {
            Ok(_) => {
                libraries.insert(library.clone(), scan_mtl(library)?);
            }
            Err(e) => {
                let what = match e.problem {
                    crate::files::FileProblem::Missing => "not found".to_string(),
                    problem => problem.to_string(),
                };
                log::warn!("{}:{line}: material library {} {what}; using grey", path.display(), library.display());
            }
        }
    }
    for (name, line) in &scan.used_materials {
        if !libraries.values().flatten().any(|m| &m.name == name) {
            log::warn!("{}:{line}: material '{name}' is not defined; using grey", path.display());
        }
    }

    // tobj asks for each library as it meets its `mtllib`, and numbers materials in that
    // order; `loaded` records the same order so tobj's material ids index into it.
    let loaded = RefCell::new(Vec::new());
    let directory = path.parent().unwrap_or(Path::new(""));
    // tobj's optional features add fields, so keep the update even where it fills nothing.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut scan.clean.as_bytes(), &options, |library| {
        let materials = libraries.get(&directory.join(library)).ok_or(tobj::LoadError::OpenFileFailed)?;
        loaded.borrow_mut().extend(materials.iter().cloned());
        let names = materials.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect();
        let stubs = materials.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() }).collect();
        Ok((stubs, names))
    })
    .map_err(|e| Error::in_file(path, format!("cannot read OBJ: {e}")))?;

    let mut textures = HashMap::new();
    let mut materials =
        loaded.into_inner().into_iter().map(|m| m.into_material(&mut textures)).collect::<Result<Vec<_>>>()?;
    let mut grey = None;
    let mut meshes = Vec::new();
    for model in models {
        let local = match model.mesh.material_id.filter(|&id| id < materials.len()) {
            Some(id) => id,
            None => *grey.get_or_insert_with(|| {
                materials.push(Material::plain("default", Vec3::splat(DEFAULT_DIFFUSE)));
                materials.len() - 1
            }),
        };
        meshes.extend(convert(model, material_offset + local));
    }
    if meshes.is_empty() {
        return Err(Error::in_file(path, "contains no faces"));
    }
    // tobj makes a vertex per distinct position/uv/normal triple: counted again, exactly.
    used.plus(GeometryBudget::of(&meshes), "the file").map_err(|trouble| Error::in_file(path, trouble))?;
    Ok((meshes, materials))
}

/// A bare OBJ as a scene: framed from the front (see [`super::Aabb::framing_pose`]), lit by
/// [`default_lights`], under the default sky.
pub fn load_bare(path: &Path) -> Result<Scene> {
    let (meshes, materials) = load_obj(path, 0)?;
    let mut scene = Scene {
        name: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        lights: default_lights(&meshes, &materials),
        meshes,
        materials,
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(vrao_ao::HeadPose::IDENTITY),
        nodes: Vec::new(),
    };
    scene.head = HeadPath::fixed(scene.bounds().framing_pose());
    Ok(scene)
}

/// The lights of a scene that names none: one point light per emissive mesh, or the
/// default sun when nothing emits.
///
/// An emitter becomes a point light at its area-weighted centroid, moved off the surface
/// along its average normal by 5% of √area (so it does not sit inside the surface it
/// stands for). Its colour is Ke / max(Ke) and its intensity max(Ke) · area: together
/// Ke · area, the radiant intensity of a Lambertian emitter along its normal. That is
/// right straight below a ceiling light and too bright sideways, the better error for
/// the usual downward-facing lamp.
pub fn default_lights(meshes: &[Mesh], materials: &[Material]) -> Vec<Light> {
    let lights = emitter_lights(meshes, materials);
    if lights.is_empty() {
        vec![Light::default_sun()]
    } else {
        lights
    }
}

/// The lights of a glTF that brings none of its own (or of a scene file placing one):
/// the default sun, always (its meshes' glow is texture detail, not the room's lamps), and
/// each emitter's point light as [`default_lights`] makes it.
pub fn sun_and_emitters(meshes: &[Mesh], materials: &[Material]) -> Vec<Light> {
    let mut lights = vec![Light::default_sun()];
    lights.extend(emitter_lights(meshes, materials));
    lights
}

/// One point light per emissive mesh ([`default_lights`]); a material's emission is its
/// factor times the mean of its emissive texture, so a mostly black map adds little
/// light and an all-black one none.
pub fn emitter_lights(meshes: &[Mesh], materials: &[Material]) -> Vec<Light> {
    let emission: Vec<Vec3> = materials.iter().map(mean_emission).collect();
    meshes.iter().filter_map(|m| emission.get(m.material).and_then(|&e| emitter_light(m, e))).collect()
}

/// A material's emitted radiance averaged over its emissive texture (sRGB texels taken
/// to linear, as the G-buffer samples them).
pub fn mean_emission(material: &Material) -> Vec3 {
    let Some(texture) = &material.emissive_texture else { return material.emissive };
    if material.emissive == Vec3::ZERO || texture.rgba8.len() < 4 {
        return material.emissive;
    }
    let linear: Vec<f64> = (0..=255u8).map(|b| f64::from(super::texture::srgb_to_linear(b))).collect();
    let mut sum = glam::DVec3::ZERO;
    for texel in texture.rgba8.chunks_exact(4) {
        sum += glam::DVec3::new(linear[texel[0] as usize], linear[texel[1] as usize], linear[texel[2] as usize]);
    }
    material.emissive * (sum / (texture.rgba8.len() / 4) as f64).as_vec3()
}

fn emitter_light(mesh: &Mesh, emissive: Vec3) -> Option<Light> {
    let peak = emissive.max_element();
    if !(peak > 0.0 && peak.is_finite()) {
        return None;
    }
    let (mut area, mut centroid, mut normal) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
    for t in mesh.indices.chunks_exact(3) {
        let corners: Option<Vec<DVec3>> =
            t.iter().map(|&i| mesh.positions.get(i as usize).map(|p| p.as_dvec3())).collect();
        let Some([a, b, c]) = corners.and_then(|c| <[DVec3; 3]>::try_from(c).ok()) else { continue };
        let cross = (b - a).cross(c - a);
        let triangle_area = 0.5 * cross.length();
        area += triangle_area;
        centroid += triangle_area * (a + b + c) / 3.0;
        normal += cross;
    }
    if area.is_nan() || area <= 0.0 {
        return None;
    }
    let offset = normal.normalize_or_zero() * 0.05 * area.sqrt();
    Some(Light::Point {
        position: mesh.origin + centroid / area + offset,
        color: emissive / peak,
        intensity: (peak as f64 * area) as f32,
    })
}

/// Reads a text file (a regular file of at most [`crate::files::MAX_FILE_BYTES`]); bytes
/// that are not UTF-8 (say, a Latin-1 comment) become U+FFFD rather than failing the load.
fn read_text(path: &Path) -> Result<String> {
    let bytes = crate::files::read_regular_file(path, crate::files::MAX_FILE_BYTES)?;
    Ok(match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}

/// The part of an OBJ or MTL line before its `#` comment.
fn strip_comment(line: &str) -> &str {
    line.split('#').next().unwrap_or("")
}

/// Parses `word` as a finite f32 (the precision tobj stores), or says which `what` it
/// was meant to be.
fn finite(word: &str, what: &str, file: &Path, line: usize) -> Result<f32> {
    match word.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(Error::at_line(file, line, format!("{what} '{word}' is not a finite number"))),
        Err(_) => Err(Error::at_line(file, line, format!("{what} '{word}' is not a number"))),
    }
}

/// What the OBJ check found.
#[derive(Debug)]
struct ObjScan {
    /// The checked statements that tobj should read.
    clean: String,
    /// Material libraries, resolved against the OBJ's directory, with their lines.
    libraries: Vec<(PathBuf, usize)>,
    /// Material names after `usemtl`, with their lines.
    used_materials: Vec<(String, usize)>,
}

/// Counts of the elements defined so far, which face indices may refer to.
#[derive(Default)]
struct Defined {
    vertices: usize,
    texcoords: usize,
    normals: usize,
}

/// One OBJ or MTL statement: its keyword and the rest of its line, comment removed.
struct Statement<'a> {
    file: &'a Path,
    line: usize,
    keyword: &'a str,
    rest: &'a str,
}

impl<'a> Statement<'a> {
    /// Line `line` (1-based) of `file`, reading `raw`.
    fn parse(file: &'a Path, line: usize, raw: &'a str) -> Statement<'a> {
        let content = strip_comment(raw).trim();
        let (keyword, rest) = content.split_once(char::is_whitespace).unwrap_or((content, ""));
        Statement { file, line, keyword, rest: rest.trim() }
    }

    /// The words after the keyword.
    fn words(&self) -> Vec<&'a str> {
        self.rest.split_whitespace().collect()
    }

    /// The words after the keyword as finite numbers, each named `what` in an error.
    fn numbers(&self, what: &str) -> Result<Vec<f32>> {
        self.rest.split_whitespace().map(|w| finite(w, what, self.file, self.line)).collect()
    }

    /// An error placed at this statement's line.
    fn at(&self, message: impl Into<String>) -> Error {
        Error::at_line(self.file, self.line, message)
    }
}

/// The OBJ check's state as it reads the file's statements in order.
struct ObjScanner<'a> {
    /// The OBJ's directory, which material libraries are resolved against.
    directory: &'a Path,
    scan: ObjScan,
    defined: Defined,
    /// The scene so far plus this file's faces (fan-triangulated) and positions.
    counted: GeometryBudget,
}

fn scan_obj(path: &Path, text: &str, used: GeometryBudget) -> Result<ObjScan> {
    let mut scanner = ObjScanner {
        directory: path.parent().unwrap_or(Path::new("")),
        scan: ObjScan { clean: String::with_capacity(text.len()), libraries: Vec::new(), used_materials: Vec::new() },
        defined: Defined::default(),
        counted: used,
    };
    for (number, raw) in text.lines().enumerate() {
        let statement = Statement::parse(path, number + 1, raw);
        match statement.keyword {
            "v" => scanner.vertex(&statement)?,
            "vt" => scanner.texcoord(&statement)?,
            "vn" => scanner.normal(&statement)?,
            "f" => scanner.face(&statement)?,
            "mtllib" => scanner.mtllib(&statement),
            "usemtl" => scanner.usemtl(&statement)?,
            "o" | "g" => scanner.scan.clean.push_str(&format!("{} {}\n", statement.keyword, statement.rest)),
            // Smoothing groups, lines, points, free-form geometry: not used.
            _ => {}
        }
    }
    Ok(scanner.scan)
}

impl ObjScanner<'_> {
    /// `v x y z [w]` (or with a vertex colour): a finite position within the coordinate
    /// limits, counted against the vertex budget.
    fn vertex(&mut self, statement: &Statement) -> Result<()> {
        let xyz = match statement.numbers("vertex coordinate")?.as_slice() {
            // x y z, optionally followed by a vertex colour (not used).
            [x, y, z] | [x, y, z, _, _, _] => [*x, *y, *z],
            [x, y, z, w] => {
                let scaled = [x / w, y / w, z / w];
                if !scaled.iter().all(|c| c.is_finite()) {
                    return Err(statement.at(format!("vertex weight w = {w} makes the position infinite")));
                }
                scaled
            }
            found => {
                let message = format!("a vertex needs 3 coordinates (x y z [w]), found {}", found.len());
                return Err(statement.at(message));
            }
        };
        let farthest = xyz.iter().fold(0.0f32, |m, c| m.max(c.abs())) as f64;
        if let Some(trouble) = super::limits::coordinate_trouble("vertex coordinate", farthest) {
            return Err(statement.at(trouble));
        }
        self.scan.clean.push_str(&format!("v {} {} {}\n", xyz[0], xyz[1], xyz[2]));
        self.defined.vertices += 1;
        let one = GeometryBudget { triangles: 0, vertices: 1, meshes: 0 };
        self.counted = self.counted.plus(one, "this vertex").map_err(|trouble| statement.at(trouble))?;
        Ok(())
    }

    /// `vt u [v [w]]`: tobj reads u and v (0 when absent).
    fn texcoord(&mut self, statement: &Statement) -> Result<()> {
        let uv = statement.numbers("texture coordinate")?;
        if !(1..=3).contains(&uv.len()) {
            let message = format!("a texture coordinate needs 1 to 3 numbers (u [v [w]]), found {}", uv.len());
            return Err(statement.at(message));
        }
        self.scan.clean.push_str(&format!("vt {} {}\n", uv[0], uv.get(1).copied().unwrap_or(0.0)));
        self.defined.texcoords += 1;
        Ok(())
    }

    /// `vn x y z`.
    fn normal(&mut self, statement: &Statement) -> Result<()> {
        if statement.numbers("normal component")?.len() != 3 {
            let found = statement.words().len();
            return Err(statement.at(format!("a normal needs 3 numbers, found {found}")));
        }
        self.scan.clean.push_str(&format!("vn {}\n", statement.rest));
        self.defined.normals += 1;
        Ok(())
    }

    /// `f v1 v2 v3 …`: every vertex names elements defined above, and the face's fan
    /// triangles are counted against the triangle budget.
    fn face(&mut self, statement: &Statement) -> Result<()> {
        let words = statement.words();
        if words.len() < 3 {
            return Err(statement.at(format!("a face needs at least 3 vertices, found {}", words.len())));
        }
        for word in &words {
            check_face_vertex(word, &self.defined).map_err(|problem| statement.at(problem.0))?;
        }
        let face = GeometryBudget { triangles: words.len() - 2, vertices: 0, meshes: 0 };
        self.counted = self.counted.plus(face, "this face").map_err(|trouble| statement.at(trouble))?;
        self.scan.clean.push_str(&format!("f {}\n", statement.rest));
        Ok(())
    }

    /// `mtllib name …`: the libraries, resolved against the OBJ's directory.
    fn mtllib(&mut self, statement: &Statement) {
        let (rest, words) = (statement.rest, statement.words());
        // A name may contain spaces; otherwise several libraries may share a line.
        let names = if self.directory.join(rest).is_file() || words.len() < 2 { vec![rest] } else { words };
        for name in names.into_iter().filter(|n| !n.is_empty()) {
            self.scan.libraries.push((self.directory.join(name), statement.line));
            self.scan.clean.push_str(&format!("mtllib {name}\n"));
        }
    }

    /// `usemtl name`.
    fn usemtl(&mut self, statement: &Statement) -> Result<()> {
        let rest = statement.rest;
        if rest.is_empty() {
            return Err(statement.at("usemtl needs a material name"));
        }
        self.scan.used_materials.push((rest.to_string(), statement.line));
        self.scan.clean.push_str(&format!("usemtl {rest}\n"));
        Ok(())
    }
}

/// Checks one face vertex `v`, `v/vt`, `v//vn` or `v/vt/vn`: every index must be an
/// integer naming an element defined above (positive from the start of the file, 1-based;
/// negative counting back from the latest). The problem is placed at its line by the caller.
fn check_face_vertex(word: &str, defined: &Defined) -> std::result::Result<(), BadFaceVertex> {
    let parts: Vec<&str> = word.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(BadFaceVertex(format!("face vertex '{word}' is not of the form v, v/vt, v//vn or v/vt/vn")));
    }
    let kinds = [
        ("face index", "vertices", defined.vertices),
        ("texture coordinate index", "texture coordinates", defined.texcoords),
        ("normal index", "normals", defined.normals),
    ];
    for (part, (what, plural, count)) in parts.iter().zip(kinds) {
        if part.is_empty() {
            continue;
        }
        let index: i64 = part
            .parse()
            .map_err(|_| BadFaceVertex(format!("{what} '{part}' in face vertex '{word}' is not an integer")))?;
        if index == 0 {
            return Err(BadFaceVertex(format!("{what} 0 is invalid (OBJ indices start at 1)")));
        }
        if index.unsigned_abs() > count as u64 {
            return Err(BadFaceVertex(format!("{what} {index} is out of range ({count} {plural} defined so far)")));
        }
    }
    Ok(())
}

/// What is wrong with one face vertex, for the caller to place at its line.
struct BadFaceVertex(String);

/// One `newmtl` block, as far as rendering uses it.
#[derive(Clone, Debug)]
struct MtlMaterial {
    name: String,
    diffuse: Option<Vec3>,
    emissive: Vec3,
    /// `map_Kd`, resolved against the MTL file's directory; known to exist.
    diffuse_texture: Option<PathBuf>,
    /// `d` (or 1 − `Tr`), in [0, 1].
    alpha: Option<f32>,
    /// `map_d`, resolved and known to exist: its alpha channel (or grey level when it has
    /// none) becomes the diffuse texture's alpha, alpha-tested at 0.5.
    alpha_texture: Option<PathBuf>,
}

impl MtlMaterial {
    /// The material with its texture decoded (once per file, via `cache`).
    fn into_material(self, cache: &mut HashMap<PathBuf, Texture>) -> Result<Material> {
        let mut diffuse_texture = match self.diffuse_texture {
            Some(path) if cache.contains_key(&path) => cache.get(&path).cloned(),
            Some(path) => Some(cache.entry(path.clone()).or_insert(load_texture(&path)?).clone()),
            None => None,
        };
        let alpha = self.alpha.unwrap_or(1.0);
        let alpha_mode = match &self.alpha_texture {
            Some(path) => {
                let (width, height, coverage) = load_alpha(path)?;
                diffuse_texture = Some(with_alpha(diffuse_texture, width, height, &coverage));
                super::AlphaMode::Mask { cutoff: 0.5 }
            }
            // A uniformly see-through material (glass): blended, which vrao alpha-tests.
            None if alpha < 1.0 => super::AlphaMode::Blend,
            None => super::AlphaMode::Opaque,
        };
        Ok(Material {
            emissive_texture: None,
            normal_texture: None,
            occlusion_texture: None,
            name: self.name,
            diffuse: self.diffuse.unwrap_or(Vec3::splat(DEFAULT_DIFFUSE)).clamp(Vec3::ZERO, Vec3::ONE),
            emissive: self.emissive,
            diffuse_texture,
            alpha,
            alpha_mode,
            // OBJ windings are not trusted.
            double_sided: true,
        })
    }
}

/// Parses and checks an MTL file. Keys used for rendering (Kd, Ke, map_Kd, d, Tr, map_d)
/// are kept; the other numeric keys (Ka, Ks, Ns, Ni, illum) are checked but dropped; unknown
/// keys are ignored; `#` starts a comment anywhere on a line.
fn scan_mtl(path: &Path) -> Result<Vec<MtlMaterial>> {
    let text = read_text(path)?;
    let directory = path.parent().unwrap_or(Path::new(""));
    let mut materials: Vec<MtlMaterial> = Vec::new();
    for (number, raw) in text.lines().enumerate() {
        let statement = Statement::parse(path, number + 1, raw);
        let (key, rest) = (statement.keyword, statement.rest);
        // Values before the first newmtl belong to no material (as in tobj): they are
        // checked, then dropped.
        match key {
            "newmtl" if rest.is_empty() => return Err(statement.at("newmtl needs a material name")),
            "newmtl" => materials.push(MtlMaterial {
                name: rest.to_string(),
                diffuse: None,
                emissive: Vec3::ZERO,
                diffuse_texture: None,
                alpha: None,
                alpha_texture: None,
            }),
            "Kd" | "Ka" | "Ks" | "Ke" => {
                let colour = mtl_colour(&statement)?;
                if let Some(m) = materials.last_mut() {
                    match key {
                        "Kd" => m.diffuse = Some(colour),
                        "Ke" => m.emissive = colour,
                        _ => {}
                    }
                }
            }
            "Ns" | "Ni" | "d" | "Tr" => {
                let value = mtl_number(&statement)?;
                if let Some(m) = materials.last_mut().filter(|_| key == "d" || key == "Tr") {
                    // Tr is transparency: 1 − d.
                    m.alpha = Some(if key == "d" { value } else { 1.0 - value });
                }
            }
            "illum" if rest.parse::<u8>().is_err() => {
                return Err(statement.at(format!("illum value '{rest}' is not an illumination model number (0-10)")));
            }
            "map_Kd" | "map_d" => {
                let texture = mtl_texture(&statement, directory)?;
                if let Some(m) = materials.last_mut() {
                    if key == "map_Kd" {
                        m.diffuse_texture = Some(texture);
                    } else {
                        m.alpha_texture = Some(texture);
                    }
                }
            }
            _ => {}
        }
    }
    Ok(materials)
}

/// An MTL colour (`Kd`, `Ka`, `Ks`, `Ke`: `r g b` or one grey level); the diffuse and
/// emitted colours must not be negative.
fn mtl_colour(statement: &Statement) -> Result<Vec3> {
    let (key, rest) = (statement.keyword, statement.rest);
    let colour = match statement.numbers(&format!("{key} value"))?.as_slice() {
        [grey] => Vec3::splat(*grey),
        [r, g, b] => Vec3::new(*r, *g, *b),
        found => return Err(statement.at(format!("{key} needs 1 or 3 numbers (r [g b]), found {}", found.len()))),
    };
    if (key == "Kd" || key == "Ke") && colour.min_element() < 0.0 {
        return Err(statement.at(format!("{key} {rest} is negative")));
    }
    // An emitter brighter than the HDR buffer holds would turn to infinity (black).
    if key == "Ke" {
        if let Some(trouble) = super::limits::radiance_trouble("Ke", colour.max_element() as f64) {
            return Err(statement.at(trouble));
        }
    }
    Ok(colour)
}

/// An MTL key of one number (`Ns`, `Ni`, `d`, `Tr`); the alpha keys `d` and `Tr` must
/// lie in [0, 1].
fn mtl_number(statement: &Statement) -> Result<f32> {
    let key = statement.keyword;
    let values = statement.numbers(&format!("{key} value"))?;
    if values.len() != 1 {
        return Err(statement.at(format!("{key} needs one number, found {}", values.len())));
    }
    let value = values[0];
    if (key == "d" || key == "Tr") && !(0.0..=1.0).contains(&value) {
        return Err(statement.at(format!("{key} {value} is not in [0, 1]")));
    }
    Ok(value)
}

/// A texture map's file (`map_Kd`, `map_d`), resolved against the MTL's `directory`:
/// it must exist and be a regular file.
fn mtl_texture(statement: &Statement, directory: &Path) -> Result<PathBuf> {
    let (key, rest) = (statement.keyword, statement.rest);
    // Options such as `-bm 1` come before the file name.
    let name = if rest.starts_with('-') { rest.split_whitespace().last().unwrap_or("") } else { rest };
    if name.is_empty() {
        return Err(statement.at(format!("{key} needs a texture file name")));
    }
    let texture = directory.join(name);
    match crate::files::check_regular_file(&texture) {
        Ok(_) => {}
        Err(e) if matches!(e.problem, crate::files::FileProblem::Missing) => {
            return Err(statement.at(format!("texture file '{name}' not found (looked for {})", texture.display())));
        }
        Err(e) => return Err(statement.at(format!("texture file '{name}' ({}) {}", texture.display(), e.problem))),
    }
    Ok(texture)
}

/// The image in a texture file (a regular file of at most [`crate::files::MAX_FILE_BYTES`]),
/// decoded under the texture limits ([`super::limits::decode_texture`]: sides up to
/// [`super::limits::MAX_TEXTURE_SIDE`]).
fn read_image(path: &Path, what: &str) -> Result<image::DynamicImage> {
    let bytes = crate::files::read_regular_file(path, crate::files::MAX_FILE_BYTES)?;
    super::limits::decode_texture(&bytes).map_err(|e| Error::in_file(path, format!("cannot decode {what}: {e}")))
}

/// Decodes an image file into RGBA8 (PNG, JPEG, TGA or BMP, by content).
fn load_texture(path: &Path) -> Result<Texture> {
    let image = read_image(path, "texture")?.into_rgba8();
    Ok(Texture {
        sampling: Default::default(),
        width: image.width(),
        height: image.height(),
        rgba8: image.into_raw().into(),
        source: Some(path.into()),
    })
}

/// An alpha map (MTL `map_d`): its alpha channel when the image has one, else its grey
/// level, as (width, height, one byte per texel).
fn load_alpha(path: &Path) -> Result<(u32, u32, Vec<u8>)> {
    let image = read_image(path, "alpha texture")?;
    let (width, height) = (image.width(), image.height());
    let coverage = if image.color().has_alpha() {
        image.into_rgba8().pixels().map(|p| p.0[3]).collect()
    } else {
        image.into_luma8().into_raw()
    };
    Ok((width, height, coverage))
}

/// `diffuse` (or a white texture of the alpha map's size) with its alpha channel replaced
/// by `coverage` (`width` × `height`), resampled to the diffuse texture's size by nearest
/// texel when the sizes differ.
fn with_alpha(diffuse: Option<Texture>, width: u32, height: u32, coverage: &[u8]) -> Texture {
    let mut texture = diffuse.unwrap_or_else(|| Texture {
        sampling: Default::default(),
        width,
        height,
        rgba8: vec![255; 4 * width as usize * height as usize].into(),
        source: None,
    });
    let (tw, th) = (texture.width as u64, texture.height as u64);
    for y in 0..th {
        for x in 0..tw {
            let (sx, sy) = (x * width as u64 / tw, y * height as u64 / th);
            let alpha = coverage.get((sy * width as u64 + sx) as usize).copied().unwrap_or(255);
            std::sync::Arc::make_mut(&mut texture.rgba8)[((y * tw + x) * 4 + 3) as usize] = alpha;
        }
    }
    texture
}

/// A tobj model as a mesh: positions recentred on their bounds, v flipped, normals
/// repaired or computed. `None` for a model without triangles.
fn convert(model: tobj::Model, material: usize) -> Option<Mesh> {
    let source = model.mesh;
    if source.indices.is_empty() {
        return None;
    }
    let count = source.positions.len() / 3;
    let world: Vec<DVec3> = source.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2]).as_dvec3()).collect();
    let (origin, positions) = Mesh::recentre(&world);
    // A file may give texture coordinates or normals to some vertices only; then tobj's
    // arrays are shorter than the positions and cannot be used.
    let uvs: Vec<Vec2> = if source.texcoords.len() == 2 * count {
        source.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect()
    } else {
        Vec::new()
    };
    let geometry = if source.normals.len() == 3 * count {
        let mut normals: Vec<Vec3> = source.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect();
        normals::repair_normals(&positions, &mut normals, &source.indices);
        let uvs = if uvs.is_empty() { vec![Vec2::ZERO; count] } else { uvs };
        Geometry { positions, normals, uvs, indices: source.indices }
    } else {
        normals::compute_normals(&positions, &uvs, &source.indices, normals::DEFAULT_CREASE_DEG)
    };
    Some(Mesh {
        colors: Vec::new(),
        tangents: Vec::new(),
        name: model.name,
        origin,
        node: None,
        positions: geometry.positions,
        normals: geometry.normals,
        uvs: geometry.uvs,
        uvs1: Vec::new(),
        indices: geometry.indices,
        material,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(text: &str) -> Result<ObjScan> {
        scan_obj(Path::new("t.obj"), text, GeometryBudget::default())
    }

    #[test]
    fn the_scene_budget_is_counted_face_by_face_on_top_of_the_scene_so_far() {
        use super::super::limits::{MAX_TRIANGLES, MAX_VERTICES};
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
        let nearly = |triangles, vertices| GeometryBudget { triangles, vertices, meshes: 0 };
        assert!(scan_obj(Path::new("t.obj"), text, nearly(MAX_TRIANGLES - 2, MAX_VERTICES - 4)).is_ok());
        let e = scan_obj(Path::new("t.obj"), text, nearly(MAX_TRIANGLES - 1, 0)).unwrap_err().to_string();
        assert!(e.starts_with("t.obj:6: this face brings the scene to 20000001 triangles and 4 vertices"), "{e}");
        let e = scan_obj(Path::new("t.obj"), text, nearly(0, MAX_VERTICES - 2)).unwrap_err().to_string();
        assert!(e.starts_with("t.obj:3: this vertex brings the scene to 0 triangles and 20000001 vertices"), "{e}");
    }

    #[test]
    fn face_indices_resolve_against_elements_defined_so_far() {
        let ok = "v 0 0 0\nv 1 0 0\nvt 0 0\nvn 0 1 0\nv 0 0 1\nf 1/1/1 -2/-1/-1 3//1\n";
        assert!(scan(ok).is_ok());
        let forward = scan("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n").unwrap_err().to_string();
        assert_eq!(forward, "t.obj:3: face index 3 is out of range (2 vertices defined so far)");
        let negative = scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n").unwrap_err().to_string();
        assert!(negative.contains("t.obj:4: face index -4 is out of range (3 vertices"), "{negative}");
        let texcoord = scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n").unwrap_err().to_string();
        assert!(texcoord.contains("texture coordinate index 1 is out of range (0 texture"), "{texcoord}");
        assert!(scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err().to_string().contains("start at 1"));
        assert!(scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n").unwrap_err().to_string().contains("not an integer"));
        assert!(scan("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err().to_string().contains("at least 3 vertices"));
        assert!(scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n").is_err());
    }

    #[test]
    fn numbers_must_be_finite_and_complete() {
        for (text, expected) in [
            ("v 0 0 0\nv 1 nan 0\n", "t.obj:2: vertex coordinate 'nan' is not a finite number"),
            ("v 1 1e39 0\n", "t.obj:1: vertex coordinate '1e39' is not a finite number"),
            ("v 1 2\n", "t.obj:1: a vertex needs 3 coordinates (x y z [w]), found 2"),
            ("vn 0 inf 0\n", "t.obj:1: normal component 'inf' is not a finite number"),
            ("vt 0,5 1\n", "t.obj:1: texture coordinate '0,5' is not a number"),
            ("v 1 1 1 0\n", "t.obj:1: vertex weight w = 0 makes the position infinite"),
        ] {
            assert_eq!(scan(text).unwrap_err().to_string(), expected);
        }
    }

    #[test]
    fn cleaned_text_keeps_what_tobj_needs() {
        let s =
            scan("# c\nv 2 4 6 2\nv 1 2 3 0.5 0.5 0.5 # colour\nvt 0.5\ns 1\nl 1 2\ng a # group\nf 1 2 1\n").unwrap();
        assert_eq!(s.clean, "v 1 2 3\nv 1 2 3\nvt 0.5 0\ng a\nf 1 2 1\n");
    }

    #[test]
    fn emitter_becomes_a_point_light_below_it() {
        // A 2 m × 1 m quad at y = 3 facing down, emitting (4, 2, 0).
        let mesh = Mesh {
            colors: Vec::new(),
            tangents: Vec::new(),
            name: "lamp".into(),
            origin: DVec3::new(0.0, 3.0, 0.0),
            positions: vec![Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 0.0)],
            normals: vec![Vec3::NEG_Y; 4],
            uvs: vec![Vec2::ZERO; 4],
            uvs1: Vec::new(),
            indices: vec![0, 2, 1, 0, 3, 2],
            material: 0,
            node: None,
        };
        let mut lamp = Material::plain("lamp", Vec3::ONE);
        lamp.emissive = Vec3::new(4.0, 2.0, 0.0);
        let lights = default_lights(std::slice::from_ref(&mesh), &[lamp]);
        let Light::Point { position, color, intensity } = lights[0] else { panic!("{lights:?}") };
        assert!((position - DVec3::new(1.0, 3.0 - 0.05 * 2f64.sqrt(), 0.5)).length() < 1e-6, "{position}");
        assert_eq!((color, intensity), (Vec3::new(1.0, 0.5, 0.0), 8.0));
        let grey = default_lights(&[mesh], &[Material::plain("grey", Vec3::ONE)]);
        assert_eq!(grey, vec![Light::default_sun()]);
    }
}
