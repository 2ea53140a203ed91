//! TOML scene files: meshes (OBJ files or built-in sets) placed in the world, lights, an
//! environment and the head pose. Unknown keys are errors, so a typo does not silently
//! fall back to a default.
//!
//! Paths: a path is relative to the scene file, so a scene and the files it names move
//! together; a path that begins with `$VRAO_SCENES/` names a file among the public scenes
//! (Cornell box, Sibenik, the HDR maps: the repository does not carry them), under the
//! folder the environment variable `VRAO_SCENES` names, wherever that is on this machine.
//! With the variable unset such a path is an error that names the variable; there is no
//! built-in fall-back, so a copied binary and a copied `assets/` behave alike. Inside this
//! repository `.cargo/config.toml` sets it to `../shared/scenes` for `cargo run` and
//! `cargo test`.
//!
//! ```toml
//! name = "cornell"                 # optional; default: the file name without extension
//!
//! [[mesh]]                         # any number; each is an OBJ, a glTF or a built-in scene's meshes
//! obj = "models/box.obj"           # or "$VRAO_SCENES/cornell_box/CornellBox-Original.obj"; or: builtin = "plane" | "crease" | "room" | "sphere" | "box"
//!                                  #   | "furnished" | "columns" | "flipped-normals" (meshes and
//!                                  #   materials only: lights and head come from this file)
//!                                  # or: gltf = "models/robot.glb" (.gltf or .glb: meshes, materials
//!                                  #   and its animation; its lights and camera are not used)
//! translate = [0.0, 0.0, 0.0]      # metres (optional)
//! rotate_deg = [0.0, 90.0, 0.0]    # about the world X, then Y, then Z axis (optional)
//! scale = 1.0                      # or [sx, sy, sz]; finite and nonzero (optional)
//! # optional: moves the entry's meshes by keyframes (world = placement · TRS(t) · mesh);
//! # each key gives the same properties, t in seconds strictly increasing (at most 10000 keys);
//! # the animation loops over the longest track of the scene; keys obey the bounds of
//! # `limits.rs` (translate within 1e6 m, scale at most 1e6 and either 0, which hides the
//! # mesh while it holds, or at least 1e-6), as eye and look_at do
//! animation = { interpolation = "linear", keys = [        # or "step"
//!     { t = 0.0, translate = [0, 0, 0], rotate_deg = [0, 0, 0], scale = 1.0 },
//!     { t = 2.0, translate = [1, 0, 0], rotate_deg = [0, 90, 0], scale = 1.0 } ] }
//!
//! [[light]]                        # no [[light]]: the rule of `obj::default_lights`
//! type = "directional"             # (emissive meshes, else a sun; with a glTF placed, the sun
//!                                  # and emissive meshes); `light = []`: no lights
//! direction = [0.3, -1.0, -0.2]    # the way the light travels; normalised on load
//! color = [1.0, 0.95, 0.9]         # linear RGB, optional (white)
//! intensity = 3.0                  # irradiance on a surface facing the light
//!
//! [[light]]
//! type = "point"
//! position = [0.0, 2.5, -1.0]
//! intensity = 6.0                  # radiant intensity: irradiance at 1 m
//!
//! [environment]                    # no [environment]: none (no sky, no environment light)
//! hdr = "sky.hdr"                  # equirectangular Radiance HDR, or: sky = "default"
//! intensity = 1.0                  # optional
//!
//! [head]                           # no [head]: framed from the front as for a bare OBJ
//! eye = [0.0, 1.6, 3.0]
//! look_at = [0.0, 1.0, 0.0]
//! # or a scripted path (t in seconds, strictly increasing):
//! # path = [{ t = 0.0, eye = [0, 1.6, 3], look_at = [0, 1, 0] },
//! #         { t = 4.0, eye = [2, 1.6, 2], look_at = [0, 1, 0] }]
//! ```
//!
//! A glTF's static meshes are placed like an OBJ's; its moving nodes' roots take the
//! placement into their `base` (so they move in the placed frame). A file placed by several
//! entries is read once; every entry's meshes count against one triangle and vertex budget
//! for the scene ([`limits::GeometryBudget`]), checked before each copy is made.
//!
//! Transforms are applied in f64 to each mesh's origin and in f32 to its (small) offsets;
//! normals use the inverse transpose, and a mirroring scale reverses the winding so that
//! triangles stay counter-clockwise around their normals.

use super::{
    builtin, limits, obj, Environment, HeadPath, Interpolation, Light, Material, Mesh, Node, NodeTracks, Scene,
};
use super::{Track, Trs};
use glam::{DMat3, DMat4, DQuat, DVec3, EulerRot};
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;
use vrao_ao::{Error, HeadPose, Result};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshEntry>>,
    light: Option<Vec<Spanned<LightEntry>>>,
    environment: Option<Spanned<EnvironmentEntry>>,
    head: Option<Spanned<HeadEntry>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    obj: Option<String>,
    gltf: Option<String>,
    builtin: Option<String>,
    animation: Option<AnimationEntry>,
    translate: Option<[f64; 3]>,
    rotate_deg: Option<[f64; 3]>,
    scale: Option<Scale>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimationEntry {
    interpolation: Option<String>,
    keys: Vec<AnimationKey>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimationKey {
    t: f64,
    translate: Option<[f64; 3]>,
    rotate_deg: Option<[f64; 3]>,
    scale: Option<Scale>,
}

/// The most keys a `[mesh.animation]` may have.
pub const MAX_ANIMATION_KEYS: usize = 10_000;

#[derive(Deserialize)]
#[serde(untagged, expecting = "scale must be a number or [x, y, z]")]
enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum LightEntry {
    Directional { direction: [f64; 3], color: Option<[f64; 3]>, intensity: f64 },
    Point { position: [f64; 3], color: Option<[f64; 3]>, intensity: f64 },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentEntry {
    hdr: Option<String>,
    sky: Option<String>,
    intensity: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadEntry {
    eye: Option<[f64; 3]>,
    look_at: Option<[f64; 3]>,
    path: Option<Vec<HeadKey>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadKey {
    t: f64,
    eye: [f64; 3],
    look_at: [f64; 3],
}

/// Loads a scene file; every error names the file and, where it can, the line.
pub fn load(path: &Path) -> Result<Scene> {
    let text = crate::files::read_regular_file_to_string(path, crate::files::MAX_TEXT_BYTES)?;
    let scene = parse(path, &text)?;
    // Without a mesh there is nothing to occlude: say so rather than render the sky.
    if scene.meshes.is_empty() {
        return Err(Error::in_file(path, "places no mesh (add a [[mesh]] with obj = \"...\" or builtin = \"...\")"));
    }
    Ok(scene)
}

/// The 1-based line holding byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Parses the scene file `text`; `path` names it in errors and anchors relative paths.
fn parse(path: &Path, text: &str) -> Result<Scene> {
    let file: SceneFile = toml::from_str(text).map_err(|e| match e.span() {
        Some(span) => Error::at_line(path, line_of(text, span.start), e.message().trim()),
        None => Error::in_file(path, e.message().trim()),
    })?;
    let directory = path.parent().unwrap_or(Path::new(""));
    let at = |span: Range<usize>, message: String| Error::at_line(path, line_of(text, span.start), message);

    let (mut meshes, mut materials, mut nodes) = (Vec::new(), Vec::new(), Vec::new());
    let mut sources = Sources::new(&file.mesh, directory);
    for entry in &file.mesh {
        let placed = load_mesh_entry(entry.get_ref(), directory, materials.len(), &mut sources)
            .map_err(|f| f.place(|m| at(entry.span(), m)))?;
        // The entry's nodes count from 0; in the scene they follow those before them.
        let offset = nodes.len();
        meshes.extend(placed.meshes.into_iter().map(|mut m| {
            m.node = m.node.map(|n| n + offset);
            m
        }));
        nodes.extend(placed.nodes.into_iter().map(|mut n| {
            n.parent = n.parent.map(|p| p + offset);
            n
        }));
        materials.extend(placed.materials);
    }

    let lights = match &file.light {
        None => {
            // Emitters where they are at time 0 (a moving mesh's positions are local).
            let still = Scene {
                name: String::new(),
                meshes: meshes.clone(),
                materials: Vec::new(),
                lights: Vec::new(),
                environment: None,
                head: HeadPath::fixed(HeadPose::IDENTITY),
                nodes: nodes.clone(),
            }
            .at_time(0.0);
            // A placed glTF keeps the sun, as it does alone (its glow is no room lamp).
            match file.mesh.iter().any(|e| e.get_ref().gltf.is_some()) {
                true => obj::sun_and_emitters(&still.meshes, &materials),
                false => obj::default_lights(&still.meshes, &materials),
            }
        }
        Some(entries) => entries
            .iter()
            .map(|e| light(e.get_ref()).map_err(|f| f.place(|m| at(e.span(), m))))
            .collect::<Result<_>>()?,
    };

    let environment = match &file.environment {
        None => None,
        Some(entry) => {
            Some(load_environment(entry.get_ref(), directory).map_err(|f| f.place(|m| at(entry.span(), m)))?)
        }
    };

    let mut scene = Scene {
        nodes,
        name: file
            .name
            .unwrap_or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()),
        meshes,
        materials,
        lights,
        environment,
        head: HeadPath::fixed(HeadPose::IDENTITY),
    };
    scene.head = match &file.head {
        None => HeadPath::fixed(scene.bounds().framing_pose()),
        Some(entry) => head_path(entry.get_ref()).map_err(|f| f.place(|m| at(entry.span(), m)))?,
    };
    Ok(scene)
}

/// Why a part of the file failed: a problem with the entry itself (reported at its line),
/// or an error from a file it names (which already says where).
enum Failure {
    Here(String),
    Elsewhere(Error),
}

impl Failure {
    /// The error, with a problem of the entry itself placed by `here`.
    fn place(self, here: impl FnOnce(String) -> Error) -> Error {
        match self {
            Failure::Here(message) => here(message),
            Failure::Elsewhere(e) => e,
        }
    }
}

impl From<super::limits::Trouble> for Failure {
    fn from(trouble: super::limits::Trouble) -> Failure {
        Failure::from(trouble.0)
    }
}

impl From<String> for Failure {
    fn from(message: String) -> Failure {
        Failure::Here(message)
    }
}

/// The prefix of paths among the public scenes (see the top of this file).
pub const SCENES_PREFIX: &str = "$VRAO_SCENES/";

/// Where the path `value` of a `what` entry points: under `$VRAO_SCENES` for a path with
/// [`SCENES_PREFIX`], otherwise relative to the scene file's `directory`.
fn resolve(directory: &Path, what: &str, value: &str) -> std::result::Result<PathBuf, Failure> {
    let Some(rest) = value.strip_prefix(SCENES_PREFIX) else { return Ok(directory.join(value)) };
    match std::env::var_os("VRAO_SCENES").filter(|v| !v.is_empty()) {
        Some(scenes) => Ok(PathBuf::from(scenes).join(rest)),
        None => Err(Failure::Here(format!(
            "{what} '{value}' is among the public scenes: set VRAO_SCENES to the folder that holds them \
             (cornell_box/, sibenik/, envmaps/)"
        ))),
    }
}

/// What one `[[mesh]]` entry adds: meshes, materials, and nodes (indices from 0).
struct Placed {
    meshes: Vec<Mesh>,
    materials: Vec<Material>,
    nodes: Vec<Node>,
}

/// The files a scene file's entries place, and the scene's triangle and vertex budget
/// ([`limits::GeometryBudget`]) as they are added. A file placed by several entries is read
/// once: its meshes are counted against the budget before each further copy is made (so
/// that one file placed many times is refused before the memory is spent), and the copies
/// share the first placement's materials.
struct Sources {
    /// How many entries still to come place each file (OBJ or glTF, as resolved).
    uses: HashMap<(bool, PathBuf), usize>,
    /// The files placed again later: their size, and their meshes and nodes as loaded
    /// (before any placement) while another copy still fits the budget.
    loaded: HashMap<(bool, PathBuf), (limits::GeometryBudget, Option<Placed>)>,
    budget: limits::GeometryBudget,
}

impl Sources {
    fn new(entries: &[Spanned<MeshEntry>], directory: &Path) -> Sources {
        let mut uses = HashMap::new();
        for entry in entries.iter().map(Spanned::get_ref) {
            if let Some(key) = entry.source(directory) {
                *uses.entry(key).or_insert(0) += 1;
            }
        }
        Sources { uses, loaded: HashMap::new(), budget: limits::GeometryBudget::default() }
    }

    /// The meshes, new materials and nodes of the file `key` (named `what` in errors),
    /// read by `load` at its first placement, copied at the others once the budget says
    /// the copy fits.
    fn place(
        &mut self,
        key: (bool, PathBuf),
        what: &str,
        load: impl FnOnce() -> std::result::Result<Placed, Failure>,
    ) -> std::result::Result<Placed, Failure> {
        let left = self.uses.get_mut(&key).map(|n| {
            *n = n.saturating_sub(1);
            *n
        });
        if let Some((size, kept)) = self.loaded.get(&key) {
            self.budget = self.budget.plus(*size, what)?;
            let copy = match (left, kept) {
                (Some(0) | None, Some(_)) => self.loaded.remove(&key).and_then(|(_, kept)| kept),
                (_, Some(kept)) => {
                    Some(Placed { meshes: kept.meshes.clone(), materials: Vec::new(), nodes: kept.nodes.clone() })
                }
                (_, None) => None,
            };
            // (Not kept only when no further copy could fit, which the budget refused above.)
            return copy.map_or_else(load, Ok);
        }
        let placed = load()?;
        let size = limits::GeometryBudget::of(&placed.meshes);
        self.budget = self.budget.plus(size, what)?;
        if left.is_some_and(|n| n > 0) {
            // A copy the budget will refuse is not kept: its size alone refuses it.
            let fits = self.budget.plus(size, what).is_ok();
            let kept = fits.then(|| Placed {
                meshes: placed.meshes.clone(),
                materials: Vec::new(),
                nodes: placed.nodes.clone(),
            });
            self.loaded.insert(key, (size, kept));
        }
        Ok(placed)
    }
}

impl MeshEntry {
    /// The file this entry places, as [`Sources`] keys it (`true` for a glTF); `None` for a
    /// built-in set or an entry that names no single file.
    fn source(&self, directory: &Path) -> Option<(bool, PathBuf)> {
        match (&self.obj, &self.gltf, &self.builtin) {
            (Some(obj), None, None) => resolve(directory, "mesh obj", obj).ok().map(|f| (false, f)),
            (None, Some(gltf), None) => resolve(directory, "mesh gltf", gltf).ok().map(|f| (true, f)),
            _ => None,
        }
    }
}

/// Refuses, as a problem of the entry, a `what` file `value` (looked for at `file`) that is
/// missing or is not a regular file (a folder, a FIFO, a device), naming what it is.
fn regular_file(file: &Path, what: &str, value: &str) -> std::result::Result<(), Failure> {
    match crate::files::check_regular_file(file) {
        Ok(_) => Ok(()),
        Err(e) if matches!(e.problem, crate::files::FileProblem::Missing) => {
            Err(Failure::Here(format!("{what} '{value}' not found (looked for {})", file.display())))
        }
        Err(e) => Err(Failure::Here(format!("{what} '{value}' ({}) {}", file.display(), e.problem))),
    }
}

fn load_mesh_entry(
    entry: &MeshEntry,
    directory: &Path,
    material_offset: usize,
    sources: &mut Sources,
) -> std::result::Result<Placed, Failure> {
    let transform = entry.transform()?;
    let (mut meshes, materials, mut nodes) = match (&entry.obj, &entry.gltf, &entry.builtin) {
        (Some(obj), None, None) => {
            let file = resolve(directory, "mesh obj", obj)?;
            regular_file(&file, "mesh obj", obj)?;
            // The OBJ's faces are counted as they are read, on top of the scene so far.
            let used = sources.budget;
            let placed = sources.place((false, file.clone()), &format!("mesh obj '{obj}'"), || {
                let (meshes, materials) =
                    obj::load_obj_within(&file, material_offset, used).map_err(Failure::Elsewhere)?;
                Ok(Placed { meshes, materials, nodes: Vec::new() })
            })?;
            (placed.meshes, placed.materials, placed.nodes)
        }
        (None, Some(gltf), None) => {
            let file = resolve(directory, "mesh gltf", gltf)?;
            regular_file(&file, "mesh gltf", gltf)?;
            // The glTF's mesh instances are counted as they are made, on top of the scene so far.
            let used = sources.budget;
            let placed = sources.place((true, file.clone()), &format!("mesh gltf '{gltf}'"), || {
                placed_gltf(&file, material_offset, used)
            })?;
            (placed.meshes, placed.materials, placed.nodes)
        }
        (None, None, Some(name)) => {
            let scene = builtin::load(name).map_err(|e| Failure::Here(e.to_string()))?;
            let mut meshes = scene.meshes;
            meshes.iter_mut().for_each(|m| m.material += material_offset);
            sources.budget = sources.budget.plus(limits::GeometryBudget::of(&meshes), &format!("builtin '{name}'"))?;
            (meshes, scene.materials, scene.nodes)
        }
        _ => {
            return Err(Failure::Here(
                "a [[mesh]] needs exactly one of obj = \"file.obj\", gltf = \"file.glb\" or builtin = \"name\"".into(),
            ));
        }
    };
    let placement = transform.as_ref().map_or(DMat4::IDENTITY, Transform::matrix);
    match &entry.animation {
        Some(animation) => {
            // A new root that the whole entry hangs from: world = placement · TRS(t) · local.
            let tracks = animation_tracks(animation)?;
            nodes.iter_mut().for_each(|n| n.parent = Some(n.parent.map_or(0, |p| p + 1)));
            nodes.insert(
                0,
                Node { name: "animation".into(), parent: None, base: placement, rest: Trs::IDENTITY, tracks },
            );
            meshes.iter_mut().for_each(|m| m.node = Some(m.node.map_or(0, |n| n + 1)));
        }
        None => {
            if let Some(transform) = transform {
                meshes.iter_mut().filter(|m| m.node.is_none()).for_each(|m| transform.apply(m));
                // Moving roots carry the placement in their base.
                nodes.iter_mut().filter(|n| n.parent.is_none()).for_each(|n| n.base = placement * n.base);
            }
        }
    }
    // Each part may be in range and their product not (a large scale of a distant mesh,
    // a far key of a large placement).
    if let Some(trouble) = meshes.iter().find_map(limits::mesh_trouble) {
        return Err(Failure::Here(trouble));
    }
    if let Some(trouble) = limits::motion_trouble(&meshes, &nodes) {
        return Err(Failure::Here(trouble));
    }
    Ok(Placed { meshes, materials, nodes })
}

/// A glTF's meshes, materials and moving nodes for a `[[mesh]] gltf = …` entry.
#[cfg(feature = "gltf")]
fn placed_gltf(
    file: &Path,
    material_offset: usize,
    used: limits::GeometryBudget,
) -> std::result::Result<Placed, Failure> {
    let content = super::gltf::load_content_within(file, material_offset, used).map_err(Failure::Elsewhere)?;
    if !content.lights.is_empty() || content.camera.is_some() {
        log::warn!(
            "{}: its lights and camera are not used when a scene file places it (the scene file gives them)",
            file.display()
        );
    }
    Ok(Placed { meshes: content.meshes, materials: content.materials, nodes: content.nodes })
}

/// Without the `gltf` feature a scene file cannot place a glTF.
#[cfg(not(feature = "gltf"))]
fn placed_gltf(file: &Path, _: usize, _: limits::GeometryBudget) -> std::result::Result<Placed, Failure> {
    Err(Failure::Elsewhere(super::gltf_not_built(file)))
}

/// The tracks of a `[mesh.animation]`: one per property the keys give (every key must give
/// the same properties), times finite, non-negative and strictly increasing.
fn animation_tracks(animation: &AnimationEntry) -> std::result::Result<NodeTracks, Failure> {
    let interpolation = animation_interpolation(animation)?;
    let keys = &animation.keys;
    let times = animation_times(keys)?;
    check_key_bounds(keys)?;
    let translation =
        property_track(keys, &times, interpolation, "translate", |k| k.translate.map(|v| finite3("translate", v)))?;
    let rotation = property_track(keys, &times, interpolation, "rotate_deg", |k| {
        k.rotate_deg.map(|v| {
            finite3("rotate_deg", v)
                .map(|d| DQuat::from_euler(EulerRot::XYZEx, d.x.to_radians(), d.y.to_radians(), d.z.to_radians()))
        })
    })?;
    let scale = property_track(keys, &times, interpolation, "scale", |k| k.scale.as_ref().map(key_scale))?;
    let tracks = NodeTracks { translation, rotation, scale };
    if tracks.is_empty() {
        return Err(Failure::Here("animation keys give none of translate, rotate_deg or scale".into()));
    }
    Ok(tracks)
}

/// An animation's interpolation: `linear` (the default) or `step`.
fn animation_interpolation(animation: &AnimationEntry) -> std::result::Result<Interpolation, Failure> {
    match animation.interpolation.as_deref().unwrap_or("linear") {
        "linear" => Ok(Interpolation::Linear),
        "step" => Ok(Interpolation::Step),
        other => Err(Failure::Here(format!("animation interpolation '{other}': expected \"linear\" or \"step\""))),
    }
}

/// The keys' times: 1 to [`MAX_ANIMATION_KEYS`] of them, finite, non-negative and
/// strictly increasing.
fn animation_times(keys: &[AnimationKey]) -> std::result::Result<Vec<f64>, Failure> {
    if keys.is_empty() || keys.len() > MAX_ANIMATION_KEYS {
        return Err(Failure::Here(format!("an animation needs 1 to {MAX_ANIMATION_KEYS} keys, found {}", keys.len())));
    }
    let times: Vec<f64> = keys.iter().map(|k| k.t).collect();
    if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
        return Err(Failure::Here(format!("animation key time {t} must be finite and ≥ 0")));
    }
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        return Err(Failure::Here(format!("animation key times {} then {} are not strictly increasing", w[0], w[1])));
    }
    Ok(times)
}

/// The bounds static values have (`limits.rs`): far translations and large scales are
/// refused, and tiny scales unless exactly 0 (which hides the mesh while it holds).
fn check_key_bounds(keys: &[AnimationKey]) -> std::result::Result<(), Failure> {
    for (k, key) in keys.iter().enumerate() {
        let far = key
            .translate
            .iter()
            .flatten()
            .find_map(|&c| limits::coordinate_trouble(&format!("animation key {} translate", k + 1), c));
        let scale = match key.scale {
            None => Vec::new(),
            Some(Scale::Uniform(s)) => vec![s],
            Some(Scale::PerAxis(s)) => s.to_vec(),
        };
        let scale =
            scale.into_iter().find_map(|c| limits::key_scale_trouble(&format!("animation key {} scale", k + 1), c));
        if let Some(trouble) = far.or(scale) {
            return Err(Failure::Here(trouble));
        }
    }
    Ok(())
}

/// One property's track. Each property is present in every key or in none (`None`).
fn property_track<T>(
    keys: &[AnimationKey],
    times: &[f64],
    interpolation: Interpolation,
    name: &str,
    value: impl Fn(&AnimationKey) -> Option<std::result::Result<T, Failure>>,
) -> std::result::Result<Option<Track<T>>, Failure> {
    let given = keys.iter().filter(|k| value(k).is_some()).count();
    if given == 0 {
        return Ok(None);
    }
    if given != keys.len() {
        return Err(Failure::Here(format!(
            "animation: {name} is given in {given} of {} keys (all or none)",
            keys.len()
        )));
    }
    let values = keys.iter().filter_map(&value).collect::<std::result::Result<Vec<T>, Failure>>()?;
    Ok(Some(Track { interpolation, times: times.to_vec(), values }))
}

/// A key's scale as a vector, finite in f64 and in the f32 the GPU reads.
fn key_scale(scale: &Scale) -> std::result::Result<DVec3, Failure> {
    let v = match *scale {
        Scale::Uniform(s) => DVec3::splat(s),
        Scale::PerAxis(s) => DVec3::from_array(s),
    };
    if v.is_finite() && v.as_vec3().is_finite() {
        Ok(v)
    } else {
        Err(Failure::Here(format!("animation scale {:?} is not finite", v.to_array())))
    }
}

fn finite3(what: &str, v: [f64; 3]) -> std::result::Result<DVec3, Failure> {
    let v = DVec3::from_array(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Failure::Here(format!("{what} {:?} is not finite", v.to_array())))
    }
}

fn non_negative(what: &str, x: f64) -> std::result::Result<f32, Failure> {
    if x.is_finite() && x >= 0.0 && x <= f32::MAX as f64 {
        Ok(x as f32)
    } else {
        Err(Failure::Here(format!("{what} {x:?} must be finite and ≥ 0")))
    }
}

/// A mesh placement: world = translate + linear · local.
struct Transform {
    linear: DMat3,
    translate: DVec3,
}

impl MeshEntry {
    /// The entry's placement, or `None` when it has none (so unplaced meshes stay exact).
    fn transform(&self) -> std::result::Result<Option<Transform>, Failure> {
        if self.translate.is_none() && self.rotate_deg.is_none() && self.scale.is_none() {
            return Ok(None);
        }
        let translate = finite3("translate", self.translate.unwrap_or_default())?;
        let degrees = finite3("rotate_deg", self.rotate_deg.unwrap_or_default())?;
        let scale = match self.scale {
            None => DVec3::ONE,
            Some(Scale::Uniform(s)) => DVec3::splat(s),
            Some(Scale::PerAxis(s)) => DVec3::from_array(s),
        };
        // Offsets are scaled in f32, so the scale must be representable there too.
        if !scale.as_vec3().is_finite() || scale.abs().min_element() == 0.0 {
            return Err(Failure::Here(format!("scale {:?} must be finite and nonzero", scale.to_array())));
        }
        let troubles = scale.to_array().into_iter().map(limits::scale_trouble);
        let far = translate.to_array().into_iter().map(|t| limits::coordinate_trouble("translate", t));
        if let Some(trouble) = troubles.chain(far).flatten().next() {
            return Err(Failure::Here(trouble));
        }
        let rotation =
            DMat3::from_euler(EulerRot::XYZEx, degrees.x.to_radians(), degrees.y.to_radians(), degrees.z.to_radians());
        Ok(Some(Transform { linear: rotation * DMat3::from_diagonal(scale), translate }))
    }
}

impl Transform {
    /// As a matrix (for nodes: a moving root's base).
    fn matrix(&self) -> DMat4 {
        DMat4::from_mat3_translation(self.linear, self.translate)
    }

    fn apply(&self, mesh: &mut Mesh) {
        let linear = self.linear.as_mat3();
        let normal_matrix = self.linear.inverse().transpose().as_mat3();
        mesh.origin = self.translate + self.linear * mesh.origin;
        mesh.positions.iter_mut().for_each(|p| *p = linear * *p);
        mesh.normals.iter_mut().for_each(|n| *n = (normal_matrix * *n).try_normalize().unwrap_or(*n));
        mesh.tangents = super::transform_tangents(&mesh.tangents, self.linear);
        if self.linear.determinant() < 0.0 {
            mesh.indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
        }
    }
}

fn light(entry: &LightEntry) -> std::result::Result<Light, Failure> {
    let colour = |c: &Option<[f64; 3]>| -> std::result::Result<glam::Vec3, Failure> {
        let c = finite3("light color", c.unwrap_or([1.0; 3]))?;
        if c.min_element() < 0.0 {
            return Err(Failure::Here(format!("light color {:?} is negative", c.to_array())));
        }
        Ok(c.as_vec3())
    };
    // Colour × intensity is what the shading multiplies in; beyond the HDR buffer's range
    // every pixel the light reaches would overflow (black after tone mapping).
    let (LightEntry::Directional { color, intensity, .. } | LightEntry::Point { color, intensity, .. }) = entry;
    // Each checked first (finite, not negative); the product from the file's own values.
    colour(color)?;
    non_negative("light intensity", *intensity)?;
    let brightest = color.unwrap_or([1.0; 3]).into_iter().fold(0.0, f64::max) * intensity;
    if let Some(trouble) = limits::radiance_trouble("light color × intensity", brightest) {
        return Err(Failure::Here(trouble));
    }
    Ok(match entry {
        LightEntry::Directional { direction, color, intensity } => {
            let d = finite3("light direction", *direction)?;
            let direction =
                d.try_normalize().ok_or_else(|| format!("light direction {:?} has no length", d.to_array()))?.as_vec3();
            Light::Directional {
                direction,
                color: colour(color)?,
                intensity: non_negative("light intensity", *intensity)?,
            }
        }
        LightEntry::Point { position, color, intensity } => Light::Point {
            position: finite3("light position", *position)?,
            color: colour(color)?,
            intensity: non_negative("light intensity", *intensity)?,
        },
    })
}

fn load_environment(entry: &EnvironmentEntry, directory: &Path) -> std::result::Result<Environment, Failure> {
    let environment = environment_unchecked(entry, directory)?;
    // The sky's brightest texel times its intensity is what the shading reads.
    let brightest = environment.texels.iter().flatten().fold(0.0f32, |m, &c| m.max(c)) as f64;
    let trouble =
        limits::radiance_trouble("environment intensity × brightest texel", environment.intensity as f64 * brightest);
    match trouble {
        Some(trouble) => Err(Failure::Here(trouble)),
        None => Ok(environment),
    }
}

fn environment_unchecked(entry: &EnvironmentEntry, directory: &Path) -> std::result::Result<Environment, Failure> {
    let intensity = non_negative("environment intensity", entry.intensity.unwrap_or(1.0))?;
    match (&entry.hdr, entry.sky.as_deref()) {
        (Some(hdr), None) => {
            let file = resolve(directory, "environment hdr", hdr)?;
            regular_file(&file, "environment hdr", hdr)?;
            Environment::load_hdr(&file, intensity).map_err(Failure::Elsewhere)
        }
        (None, Some("default")) => Ok(Environment { intensity, ..Environment::default_sky() }),
        (None, Some(other)) => Err(Failure::Here(format!("unknown sky '{other}'; available: default"))),
        _ => Err(Failure::Here("[environment] needs exactly one of hdr = \"file.hdr\" or sky = \"default\"".into())),
    }
}

fn head_pose(eye: [f64; 3], look_at: [f64; 3]) -> std::result::Result<HeadPose, Failure> {
    let (eye, target) = (finite3("eye", eye)?, finite3("look_at", look_at)?);
    // The head is where the frame is drawn from: as far as any vertex may be.
    let far = eye.to_array().into_iter().find_map(|c| limits::coordinate_trouble("eye", c));
    let far = far.or_else(|| target.to_array().into_iter().find_map(|c| limits::coordinate_trouble("look_at", c)));
    if let Some(trouble) = far {
        return Err(Failure::Here(trouble));
    }
    HeadPose::look_at(eye, target)
        .ok_or_else(|| Failure::Here(format!("eye {:?} and look_at {:?} coincide", eye.to_array(), target.to_array())))
}

fn head_path(entry: &HeadEntry) -> std::result::Result<HeadPath, Failure> {
    match (entry.eye, entry.look_at, &entry.path) {
        (Some(eye), Some(look_at), None) => Ok(HeadPath::fixed(head_pose(eye, look_at)?)),
        (None, None, Some(path)) if !path.is_empty() => {
            let mut keys: Vec<(f64, HeadPose)> = Vec::with_capacity(path.len());
            for key in path {
                let previous = keys.last().map(|k| k.0);
                if !key.t.is_finite() || previous.is_some_and(|p| key.t <= p) {
                    return Err(Failure::Here(format!(
                        "head path time t = {:?} must be finite and later than the key before",
                        key.t
                    )));
                }
                keys.push((key.t, head_pose(key.eye, key.look_at)?));
            }
            Ok(HeadPath { keys })
        }
        _ => Err(Failure::Here("[head] needs eye and look_at, or a non-empty path of { t, eye, look_at } keys".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn parse_str(text: &str) -> Result<Scene> {
        parse(Path::new("scene.toml"), text)
    }

    fn error(text: &str) -> String {
        parse_str(text).err().map(|e| e.to_string()).unwrap_or_else(|| panic!("accepted: {text}"))
    }

    #[test]
    fn builtin_meshes_lights_environment_and_head() {
        let scene = parse_str(
            r#"
name = "two planes"
[[mesh]]
builtin = "plane"
[[mesh]]
builtin = "sphere"
translate = [10, 0, 0]
[[light]]
type = "directional"
direction = [0, -2, 0]
intensity = 2
[[light]]
type = "point"
position = [1, 2, 3]
color = [1, 0.5, 0]
intensity = 5.0
[environment]
sky = "default"
intensity = 0.5
[head]
path = [{ t = 0, eye = [0, 1.6, 3], look_at = [0, 1, 0] }, { t = 2.5, eye = [1, 1.6, 3], look_at = [0, 1, 0] }]
"#,
        )
        .unwrap();
        assert_eq!(scene.name, "two planes");
        assert_eq!(scene.meshes.len(), 3);
        assert_eq!(scene.materials.len(), 2);
        assert_eq!(scene.meshes[2].material, 1, "the second set's materials are offset");
        assert_eq!(scene.lights[0], Light::Directional { direction: Vec3::NEG_Y, color: Vec3::ONE, intensity: 2.0 });
        assert!(matches!(scene.lights[1], Light::Point { intensity: 5.0, .. }));
        assert_eq!(scene.environment.as_ref().map(|e| e.intensity), Some(0.5));
        assert_eq!(scene.head.keys.len(), 2);
        // The sphere set's own floor moved with it.
        let bounds = scene.bounds();
        assert!((bounds.max.x - 30.0).abs() < 1e-9 && (bounds.min.x + 20.0).abs() < 1e-9, "{bounds:?}");
        let sphere = &scene.meshes[2];
        assert!((sphere.origin - DVec3::new(10.0, 1.0, 0.0)).length() < 1e-9);
    }

    #[test]
    fn defaults_frame_the_scene_with_no_environment() {
        let scene = parse_str("[[mesh]]\nbuiltin = \"box\"\n").unwrap();
        assert_eq!(scene.name, "scene");
        assert!(scene.environment.is_none());
        assert_eq!(scene.lights, vec![Light::default_sun()]);
        assert!(scene.head.keys[0].1.position.z > 1.0, "in front of the box");
        assert!(parse_str("light = []\n").unwrap().lights.is_empty());
    }

    #[test]
    fn rotation_scale_and_mirroring() {
        let text = "[[mesh]]\nbuiltin = \"crease\"\nrotate_deg = [0, 90, 0]\nscale = [-1, 1, 1]\n";
        let scene = parse_str(text).unwrap();
        // The wall faced +Z; mirrored in x it still faces +Z, then a quarter turn about Y
        // turns +Z into +X.
        let wall = &scene.meshes[1];
        assert!(wall.normals.iter().all(|n| n.abs_diff_eq(Vec3::X, 1e-6)), "{:?}", wall.normals[0]);
        for t in wall.indices.chunks(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| wall.positions[i as usize]);
            assert!((b - a).cross(c - a).dot(Vec3::X) > 0.0, "winding follows the mirrored normal");
        }
    }

    #[test]
    fn syntax_and_unknown_keys_name_the_line() {
        assert!(error("name = \"x\"\n[[mesh]\n").starts_with("scene.toml:2:"));
        let unknown = error("[[mesh]]\nbuiltin = \"plane\"\ncolour = 3\n");
        assert!(unknown.starts_with("scene.toml:3:") && unknown.contains("colour"), "{unknown}");
        let light = error("[[light]]\ntype = \"spot\"\nintensity = 1\n");
        assert!(light.starts_with("scene.toml:") && light.contains("spot"), "{light}");
    }

    #[test]
    fn semantic_errors_name_the_value() {
        for (text, expected) in [
            ("\n[[mesh]]\nbuiltin = \"teapot\"\n", "scene.toml:2: unknown builtin scene 'teapot'"),
            ("[[mesh]]\nobj = \"nowhere.obj\"\n", "scene.toml:1: mesh obj 'nowhere.obj' not found"),
            ("[[mesh]]\nbuiltin = \"plane\"\nscale = 0\n", "scene.toml:1: scale [0.0, 0.0, 0.0] must be finite"),
            ("[[mesh]]\nbuiltin = \"plane\"\nscale = [1, 1e300, 1]\n", "scale [1.0, 1e300, 1.0] must be finite"),
            ("[[mesh]]\nbuiltin = \"plane\"\ntranslate = [0, nan, 0]\n", "translate [0.0, NaN, 0.0] is not finite"),
            ("[[mesh]]\n", "needs exactly one of obj"),
            ("[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = -1\n", "light intensity -1.0 must be"),
            ("[[light]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nintensity = 1\n", "has no length"),
            (
                "[head]\neye = [1, 2, 3]\nlook_at = [1, 2, 3]\n",
                "scene.toml:1: eye [1.0, 2.0, 3.0] and look_at [1.0, 2.0, 3.0] coincide",
            ),
            ("[head]\neye = [1, 2, 3]\n", "[head] needs eye and look_at"),
            (
                "[head]\npath = [{ t = 1, eye = [0, 0, 1], look_at = [0, 0, 0] }, { t = 1, eye = [0, 0, 2], look_at = [0, 0, 0] }]\n",
                "t = 1.0 must be finite and later",
            ),
            ("[environment]\nsky = \"night\"\n", "unknown sky 'night'"),
            ("[environment]\nhdr = \"none.hdr\"\n", "environment hdr 'none.hdr' not found"),
            ("[environment]\nsky = \"default\"\nintensity = inf\n", "environment intensity inf must be"),
        ] {
            let message = error(text);
            assert!(message.contains(expected), "{message:?} should contain {expected:?}");
        }
    }

    #[test]
    fn far_keys_heads_and_motion_are_refused_and_scale_zero_keys_hide() {
        let mesh = "[[mesh]]\nbuiltin = \"box\"\n";
        let keys = |a: &str, b: &str| format!("{mesh}animation = {{ keys = [{{ t = 0, {a} }}, {{ t = 1, {b} }}] }}\n");
        for (text, expected) in [
            (keys("translate = [0, 0, 0]", "translate = [1e30, 0, 0]"), "scene.toml:1: animation key 2 translate 1e30 m is farther than 1e6 m"),
            (keys("translate = [0, 0, 0]", "translate = [0, -3e38, 0]"), "animation key 2 translate -3e38 m is farther"),
            (keys("scale = 1", "scale = 1e30"), "scene.toml:1: animation key 2 scale 1e30 is larger than 1e6"),
            (keys("scale = [1, 1e-30, 1]", "scale = 1"), "animation key 1 scale 1e-30 is smaller than 1e-6 and not 0"),
            // Each value in range, their product not.
            (format!("{mesh}translate = [9e5, 0, 0]\nanimation = {{ keys = [{{ t = 0, translate = [0, 0, 0] }}, {{ t = 1, translate = [9e5, 0, 0] }}] }}\n"), "scene.toml:1: moving mesh"),
            (format!("{mesh}[head]\neye = [1e30, 1, 0]\nlook_at = [0, 0, 0]\n"), "scene.toml:3: eye 1e30 m is farther than 1e6 m"),
            (format!("{mesh}[head]\neye = [0, 1, 0]\nlook_at = [0, 0, -2e6]\n"), "look_at -2e6 m is farther"),
            (format!("{mesh}[head]\npath = [{{ t = 0, eye = [0, 1, 2], look_at = [0, 0, 0] }}, {{ t = 1, eye = [0, 1, 3e38], look_at = [0, 0, 0] }}]\n"), "eye 3e38 m is farther"),
        ] {
            let message = error(&text);
            assert!(message.contains(expected), "{message:?} should contain {expected:?}");
        }
        let moving = parse_str(&format!("{mesh}translate = [9e5, 0, 0]\nanimation = {{ keys = [{{ t = 0, translate = [0, 0, 0] }}, {{ t = 1, translate = [-1e5, 0, 0] }}] }}\n"));
        assert!(moving.is_ok(), "{:?}", moving.err());
        // A scale key of exactly 0 hides the box while it holds: loaded, every value finite.
        let scene = parse_str(&keys("scale = 1", "scale = [0, 0, 0]")).unwrap();
        for t in [0.0, 0.5, 1.0] {
            let still = scene.at_time(t);
            assert!(still
                .meshes
                .iter()
                .all(|m| m.origin.is_finite() && m.positions.iter().chain(&m.normals).all(|v| v.is_finite())));
        }
        let bounds = scene.bounds();
        assert!(bounds.min.is_finite() && bounds.max.is_finite());
    }

    fn scratch(name: &str) -> crate::test_dir::TestDir {
        crate::test_dir::TestDir::new(&format!("scene-file-{name}"))
    }

    #[cfg(unix)]
    #[test]
    fn a_named_file_that_is_a_fifo_device_or_folder_is_named_as_what_it_is() {
        let dir = scratch("special");
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj")).unwrap();
        std::fs::create_dir(dir.join("folder.glb")).unwrap();
        let fifo = std::process::Command::new("mkfifo").arg(dir.join("pipe.hdr")).status().is_ok_and(|s| s.success());
        let scene = dir.join("scene.toml");
        let mut cases = vec![
            (
                "[[mesh]]\nobj = \"zero.obj\"\n",
                "scene.toml:1: mesh obj 'zero.obj' (",
                "zero.obj) is a character device, not a regular file",
            ),
            (
                "[[mesh]]\ngltf = \"folder.glb\"\n",
                "scene.toml:1: mesh gltf 'folder.glb' (",
                "folder.glb) is a directory, not a regular file",
            ),
        ];
        if fifo {
            cases.push((
                "[[mesh]]\nbuiltin = \"box\"\n[environment]\nhdr = \"pipe.hdr\"\n",
                "scene.toml:3: environment hdr 'pipe.hdr' (",
                "pipe.hdr) is a FIFO (named pipe), not a regular file",
            ));
        }
        for (text, starts, ends) in cases {
            std::fs::write(&scene, text).unwrap();
            let e = load(&scene).unwrap_err().to_string();
            assert!(e.contains(starts) && e.ends_with(ends), "{e}");
        }
    }

    #[cfg(feature = "gltf")]
    #[test]
    fn a_file_placed_many_times_is_refused_at_the_placement_that_passes_the_scene_budget() {
        // The sweep's case: one 2 M-triangle glTF (three vertices with their normals, one
        // triangle's indices repeated) placed 30 times. Read once; refused at the 11th
        // placement, before its copy is made, naming that entry's line.
        let dir = scratch("budget");
        let triangles = 2_000_000u32;
        let corners = [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let mut bin: Vec<u8> = corners.iter().flat_map(|f| f.to_le_bytes()).collect();
        bin.extend((0..3 * triangles).flat_map(|i| ((i % 3) as u16).to_le_bytes()));
        std::fs::write(dir.join("big.bin"), &bin).unwrap();
        let gltf = format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":2}},"indices":1}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC3"}}],"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":72,"byteLength":{}}},{{"buffer":0,"byteOffset":36,"byteLength":36}}],"buffers":[{{"byteLength":{},"uri":"big.bin"}}]}}"#,
            3 * triangles,
            6 * triangles,
            bin.len()
        );
        std::fs::write(dir.join("big.gltf"), gltf).unwrap();
        let entries: String =
            (0..30).map(|i| format!("[[mesh]]\ngltf = \"big.gltf\"\ntranslate = [{i}, 0, 0]\n")).collect();
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, &entries).unwrap();
        let started = std::time::Instant::now();
        let e = load(&scene).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}:31: mesh gltf 'big.gltf' brings the scene to 22000000 triangles",
                scene.display()
            )) && e.contains("more than vrao's limit of 20000000 triangles"),
            "{e}"
        );
        assert!(started.elapsed().as_secs() < 10, "{:?}", started.elapsed());
        // Ten placements fit, and share the first one's materials.
        let ten: String = entries.lines().take(30).map(|l| format!("{l}\n")).collect();
        std::fs::write(&scene, ten).unwrap();
        let scene = load(&scene).unwrap();
        assert_eq!(scene.triangle_count(), 20_000_000);
        assert_eq!(scene.materials.len(), 1);
        assert!((scene.meshes[9].origin.x - 9.0 - scene.meshes[0].origin.x).abs() < 1e-9);
    }

    #[test]
    fn line_numbers_count_from_one() {
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 99), 3);
    }
}
