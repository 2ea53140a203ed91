//! glTF 2.0 loading: `.gltf` (JSON with external or data-URI buffers and images) and
//! `.glb` (binary, with its BIN chunk).
//!
//! The `gltf` crate parses and validates the JSON (every index names an element that
//! exists); everything the JSON cannot say is checked here before it is used: the GLB
//! container, each buffer's bytes, every accessor's byte range against its buffer view and
//! buffer, finite numbers, indices against vertex counts, node cycles, key times, and a
//! bound on every count ([`MAX_FILE_BYTES`], [`MAX_TRIANGLES`], ...). Accessors are decoded
//! here rather than by the crate's readers, which assume valid ranges: dense or sparse
//! (substituted over their view or over zeros), in the component types glTF allows for each
//! use, `KHR_mesh_quantization`'s included (`accessors.rs` holds the table); a quantized
//! mesh's node transform dequantizes it. Anything wrong is one [`Error::Input`] line naming
//! the file and the element.
//!
//! What is read: the default scene (else the first; else every root node) with its
//! TRS and matrix transforms; triangle primitives (indexed u8/u16/u32 or not; strips and
//! fans become triangle lists; points and lines are skipped with one warning); POSITION,
//! NORMAL (computed as for OBJ when missing), TEXCOORD_0 and TEXCOORD_1 (each texture
//! reads the set its `texCoord`, or its `KHR_texture_transform`'s, names), TANGENT, COLOR_0
//! (times the base colour and alpha); the base-colour factor and texture; `alphaMode`
//! OPAQUE / MASK (`alphaCutoff`, default 0.5) / BLEND (see [`AlphaMode::Blend`]);
//! `doubleSided` (single-sided materials are culled from behind, [`Material::double_sided`]);
//! the emissive factor × texture × `KHR_materials_emissive_strength`; a file without
//! punctual lights gets the default sun and, for each emitter, a point light weighted by
//! its emissive texture's mean ([`obj::sun_and_emitters`]); normal textures (scale) and
//! occlusion textures (strength); each texture's sampler (wrap, filters, mipmaps) and `KHR_texture_transform`;
//! `KHR_lights_punctual` directional, point and spot lights (intensities taken as vrao's
//! units: lux as irradiance, candela as radiant intensity); the first camera's node as
//! the head pose; translation, rotation and scale animation channels (STEP, LINEAR,
//! CUBICSPLINE).
//!
//! Not read, one warning line per file (`Warnings`): points and lines, skins and morph
//! targets (drawn in the bind pose), weight animations, texture sets beyond 1,
//! metallic-roughness, light `range`, unknown optional extensions. Lights hang where their
//! nodes are at time 0 (they do not move).
//!
//! Motion: only meshes below an animated node keep a [`Node`]; static geometry is baked
//! into world space (f64 transform, then [`Mesh::recentre`], exactly as the OBJ loader
//! recentres), so a still glTF gives `Scene::nodes` empty. Static ancestors of an animated
//! node fold into its `base`; a matrix node below an animated one becomes a node whose
//! `base` is the matrix.

mod accessors;
mod files;

use super::normals::{self, Geometry};
use super::{
    obj, AlphaMode, Environment, HeadPath, Interpolation, Light, Material, Mesh, Node, NodeTracks, Scene, Texture,
    Track, Trs,
};
use ::gltf::json;
use ::gltf::mesh::Mode;
use accessors::Use;
use files::{load_buffers, read_bounded, resolve_uri, split_glb};
use glam::{DMat3, DMat4, DQuat, DVec3, Vec2, Vec3, Vec4};
use std::collections::{BTreeSet, HashMap};
use std::path::Path;
use vrao_ao::{Error, HeadPose, Result};

pub use files::decode_base64;

/// The largest `.gltf`/`.glb`, external buffer or image file read (1 GiB, as every model file).
pub const MAX_FILE_BYTES: u64 = crate::files::MAX_FILE_BYTES;
/// The most triangles over every drawn mesh instance: the scene's budget
/// ([`super::limits::MAX_TRIANGLES`], 20 million).
pub const MAX_TRIANGLES: usize = super::limits::MAX_TRIANGLES;
/// The most vertices over every drawn mesh instance ([`super::limits::MAX_VERTICES`], 20 million).
pub const MAX_VERTICES: usize = super::limits::MAX_VERTICES;
/// The most nodes a file may declare.
pub const MAX_NODES: usize = 100_000;
/// The most animation keys over all channels (10 million).
pub const MAX_KEYS: usize = 10_000_000;
/// The largest texture side in texels ([`super::limits::MAX_TEXTURE_SIDE`]).
pub const MAX_TEXTURE_SIDE: u32 = super::limits::MAX_TEXTURE_SIDE;
/// The most elements one accessor may declare (more than any bound above needs).
const MAX_ACCESSOR_COUNT: usize = 3 * MAX_TRIANGLES;

/// Extensions whose meaning vrao honours; a file that requires any other is refused.
/// (`KHR_mesh_quantization` only widens the accessor types, which are all decoded here.)
pub const SUPPORTED_EXTENSIONS: [&str; 4] =
    ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_mesh_quantization", "KHR_texture_transform"];

/// What a glTF file contributes to a scene: the scene-file loader places it, the bare
/// loader ([`load`]) frames and lights it.
#[derive(Clone, Debug)]
pub struct Content {
    /// Meshes; static ones in world space, moving ones in their node's frame.
    pub meshes: Vec<Mesh>,
    /// Materials; [`Mesh::material`] counts from the `material_offset` given to [`load_content`].
    pub materials: Vec<Material>,
    /// The motion hierarchy; [`Mesh::node`] indexes it from 0.
    pub nodes: Vec<Node>,
    /// The punctual lights (`KHR_lights_punctual`), in world space.
    pub lights: Vec<Light>,
    /// The first camera's pose, if the default scene has a camera.
    pub camera: Option<HeadPose>,
    /// What the file asks for that vrao leaves out, one line each (also logged).
    pub warnings: Vec<String>,
}

/// A glTF file as a scene: its camera as the head pose (else framed as a bare OBJ), its
/// punctual lights (else the default sun and its emitters, [`obj::sun_and_emitters`]),
/// under the default sky.
pub fn load(path: &Path) -> Result<Scene> {
    let content = load_content(path, 0)?;
    let mut scene = Scene {
        name: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        meshes: content.meshes,
        materials: content.materials,
        lights: Vec::new(),
        environment: Some(Environment::default_sky()),
        head: HeadPath::fixed(HeadPose::IDENTITY),
        nodes: content.nodes,
    };
    scene.lights = if content.lights.is_empty() {
        // Emitters where they are at time 0 (a moving emitter's positions are local).
        let still = scene.at_time(0.0);
        obj::sun_and_emitters(&still.meshes, &still.materials)
    } else {
        content.lights
    };
    scene.head = HeadPath::fixed(content.camera.unwrap_or_else(|| scene.bounds().framing_pose()));
    Ok(scene)
}

/// Reads a `.gltf` or `.glb`. Material indices start at `material_offset`.
pub fn load_content(path: &Path, material_offset: usize) -> Result<Content> {
    load_content_within(path, material_offset, super::limits::GeometryBudget::default())
}

/// [`load_content`] into a scene that already holds `used` triangles and vertices: the
/// file's mesh instances are counted on top of them as they are made, so a file that
/// would pass the scene's budget is refused before its geometry is all in memory.
pub fn load_content_within(
    path: &Path,
    material_offset: usize,
    used: super::limits::GeometryBudget,
) -> Result<Content> {
    let bytes = read_bounded(path, path)?;
    let (json_bytes, bin) = if bytes.starts_with(b"glTF") {
        let (json, bin) = split_glb(path, &bytes)?;
        (json.to_vec(), bin.map(<[u8]>::to_vec))
    } else {
        (bytes, None)
    };
    // A UTF-8 byte-order mark is not JSON (and glTF asks files to go without one), but
    // editors write it: read past it, as the sample viewer does.
    let json_text = json_bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&json_bytes);
    let mut root: json::Root = json::deserialize::from_slice(json_text)
        .map_err(|e| Error::in_file(path, format!("not valid glTF JSON: {e}")))?;
    drop(json_bytes);

    let mut warnings = Warnings::default();
    for required in &root.extensions_required {
        if !SUPPORTED_EXTENSIONS.contains(&required.as_str()) {
            return Err(Error::in_file(path, format!("requires extension {required}, which vrao does not support")));
        }
    }
    for used in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&used.as_str()) {
            warnings.extensions.insert(used.clone());
        }
    }
    // The crate's validation refuses required extensions it has no feature for; vrao
    // decodes quantised accessors itself, so that one is checked above instead.
    root.extensions_required.retain(|e| e != "KHR_mesh_quantization");
    if root.nodes.len() > MAX_NODES {
        return Err(Error::in_file(path, format!("{} nodes, more than vrao's limit of {MAX_NODES}", root.nodes.len())));
    }
    precheck(&root).map_err(|Problem(m)| Error::in_file(path, m))?;
    let document = ::gltf::Document::from_json(root).map_err(|e| Error::in_file(path, first_line(&e.to_string())))?;

    let buffers = load_buffers(path, &document, bin)?;
    let mut loader = Loader {
        path,
        document: &document,
        buffers,
        warnings,
        images: HashMap::new(),
        texture_bytes: 0,
        materials: Vec::new(),
        material_of: HashMap::new(),
        material_offset,
        primitives: HashMap::new(),
        budget: used,
    };
    let mut content = loader.build()?;
    check_limits(path, &content)?;
    content.warnings = loader.warnings.lines(path);
    for line in &content.warnings {
        log::warn!("{line}");
    }
    Ok(content)
}

/// Refuses, naming the file, what lies beyond what the renderer can draw (`limits.rs`,
/// as for OBJ and scene files): static geometry beyond 10⁶ m, emission or lights
/// brighter than the HDR buffer holds. (Moving meshes are in their node's frame.)
fn check_limits(path: &Path, content: &Content) -> Result<()> {
    use super::limits::{coordinate_trouble, mesh_trouble, radiance_trouble};
    let meshes = content.meshes.iter().filter(|m| m.node.is_none()).find_map(mesh_trouble);
    let emitters = content
        .materials
        .iter()
        .find_map(|m| radiance_trouble(&format!("material '{}' emission", m.name), m.emissive.max_element() as f64));
    let lights = content.lights.iter().find_map(|light| {
        let (colour, intensity, position) = match *light {
            Light::Directional { color, intensity, .. } => (color, intensity, None),
            Light::Point { color, intensity, position } | Light::Spot { color, intensity, position, .. } => {
                (color, intensity, Some(position))
            }
        };
        let far = position.and_then(|p| coordinate_trouble("light position", p.abs().max_element()));
        far.or_else(|| radiance_trouble("light colour × intensity", (colour * intensity).max_element() as f64))
    });
    match meshes.or(emitters).or(lights) {
        Some(trouble) => Err(Error::in_file(path, trouble)),
        None => Ok(()),
    }
}

/// What is wrong with a file, for the caller to name the file (and element) with.
struct Problem(String);

impl From<String> for Problem {
    fn from(message: String) -> Problem {
        Problem(message)
    }
}

/// What the crate's validation leaves out and its accessors would panic on (found by
/// fuzzing and by reading gltf 1.4.1): animation channel targets (node index and path), a
/// spot light without its cone, a primitive's POSITION accessor that does not exist (the
/// crate's own primitive check indexes the accessors with it before checking it), and an
/// image without the source `Image::source` unwraps (a bufferView needs a mimeType, as
/// glTF requires; otherwise a uri). The rest of the accessor, sparse, image, texture and
/// sampler getters unwrap only what the crate's validation has checked (indices in range,
/// enumerations valid, a texture's source present).
fn precheck(root: &json::Root) -> std::result::Result<(), Problem> {
    use json::validation::Checked;
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (_, Some(_), None) => return Err(Problem(format!("image {i}: has a bufferView but no mimeType"))),
            (None, None, _) => return Err(Problem(format!("image {i}: has neither a uri nor a bufferView"))),
            _ => {}
        }
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &primitive.attributes {
                if accessor.value() >= root.accessors.len() {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "an attribute".into(),
                    };
                    return Err(Problem(format!(
                        "mesh {m} primitive {p}: {name} accessor {} does not exist",
                        accessor.value()
                    )));
                }
            }
        }
    }
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let node = channel.target.node.value();
            if node >= root.nodes.len() {
                return Err(Problem(format!("animation {a} channel {c}: target node {node} does not exist")));
            }
            if !matches!(channel.target.path, Checked::Valid(_)) {
                return Err(Problem(format!(
                    "animation {a} channel {c}: target path is not one of the glTF properties"
                )));
            }
            if channel.sampler.value() >= animation.samplers.len() {
                return Err(Problem(format!("animation {a} channel {c}: sampler does not exist")));
            }
        }
    }
    let lights = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
    for (i, light) in lights.map_or(&[][..], |l| &l.lights[..]).iter().enumerate() {
        use json::extensions::scene::khr_lights_punctual::Type;
        if matches!(light.type_, Checked::Valid(Type::Spot)) && light.spot.is_none() {
            return Err(Problem(format!("light {i}: a spot light needs its \"spot\" cone angles")));
        }
    }
    Ok(())
}

/// The first line of a (possibly multi-line) message.
fn first_line(message: &str) -> String {
    let mut lines = message.lines().filter(|l| !l.trim().is_empty());
    let first = lines.next().unwrap_or("").trim().to_string();
    match lines.count() {
        0 => first,
        more => format!("{first} (and {more} more)"),
    }
}

/// What was read but not honoured, reported as one warning line per kind at the end.
#[derive(Default)]
struct Warnings {
    extensions: BTreeSet<String>,
    ignored: BTreeSet<&'static str>,
    /// Primitives whose TANGENT was degenerate and left out, each with its first bad vertex.
    derived_tangents: Vec<String>,
}

impl Warnings {
    /// One line for the unsupported extensions, one for the other features left out.
    fn lines(&self, path: &Path) -> Vec<String> {
        let mut lines = Vec::new();
        if !self.extensions.is_empty() {
            let list: Vec<&str> = self.extensions.iter().map(String::as_str).collect();
            lines.push(format!("{}: optional extensions not supported (ignored): {}", path.display(), list.join(", ")));
        }
        if !self.ignored.is_empty() {
            let list: Vec<&str> = self.ignored.iter().copied().collect();
            lines.push(format!("{}: not supported (ignored): {}", path.display(), list.join("; ")));
        }
        if !self.derived_tangents.is_empty() {
            let more = match self.derived_tangents.len() {
                n if n > 4 => format!(" and {} more", n - 4),
                _ => String::new(),
            };
            lines.push(format!(
                "{}: TANGENT zero or parallel to NORMAL in {}{more}: those primitives' tangents are derived from \
                 their texture coordinates instead",
                path.display(),
                self.derived_tangents[..self.derived_tangents.len().min(4)].join(", ")
            ));
        }
        lines
    }
}

/// One primitive decoded in its mesh's local frame.
#[derive(Clone)]
struct LocalPrimitive {
    name: String,
    geometry: Geometry,
    /// What follows the vertices of `geometry` besides its own attributes.
    extras: VertexExtras,
    /// Index into the loaded materials (before the offset).
    material: usize,
}

/// The vertex attributes [`Geometry`] does not hold, each one per vertex or empty.
#[derive(Clone, Default)]
struct VertexExtras {
    /// TEXCOORD_1.
    uvs1: Vec<Vec2>,
    /// COLOR_0.
    colors: Vec<Vec4>,
    /// TANGENT.
    tangents: Vec<Vec4>,
}

/// A triangle primitive's vertex attributes as read, before normals.
struct Attributes {
    positions: Vec<Vec3>,
    /// The triangle list (strips and fans unrolled), every index below the positions' count.
    indices: Vec<u32>,
    /// TEXCOORD_0, one per position, or empty.
    uvs: Vec<Vec2>,
    /// TEXCOORD_1, one per position, or empty.
    uvs1: Vec<Vec2>,
    /// COLOR_0, one per position, or empty.
    colors: Vec<Vec4>,
    /// TANGENT, one per position, or empty.
    tangents: Vec<Vec4>,
}

/// State of one load.
struct Loader<'a> {
    path: &'a Path,
    document: &'a ::gltf::Document,
    buffers: Vec<std::sync::Arc<Vec<u8>>>,
    warnings: Warnings,
    /// Decoded images by their source (a URI, or a buffer view): image entries naming one
    /// file are decoded, held and uploaded once.
    images: HashMap<ImageSource, Texture>,
    /// Bytes of decoded texels over the distinct images so far (bounded).
    texture_bytes: u64,
    materials: Vec<Material>,
    /// vrao material index by glTF material index (`None` = the default material).
    material_of: HashMap<Option<usize>, usize>,
    material_offset: usize,
    /// Decoded primitives by glTF mesh index (a mesh drawn by several nodes is read once).
    primitives: HashMap<usize, Vec<LocalPrimitive>>,
    /// Drawn so far, over every instance (bounded).
    budget: super::limits::GeometryBudget,
}

/// Where an image's bytes come from: image entries with the same source are one image.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum ImageSource {
    Uri(String),
    View(usize),
}

/// Where a node sits while the hierarchy is walked.
#[derive(Clone, Copy)]
struct Parent {
    /// World transform of the static chain above (used while no ancestor moves).
    world: DMat4,
    /// The nearest moving ancestor's node, once there is one.
    node: Option<usize>,
}

/// The nodes a glTF's scene starts from: the default scene's (or the first scene's), or
/// without a scene every node that is nobody's child.
fn scene_roots(document: &::gltf::Document) -> Vec<::gltf::Node<'_>> {
    match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child.
            let mut is_child = vec![false; document.nodes().len()];
            document.nodes().flat_map(|n| n.children()).for_each(|c| is_child[c.index()] = true);
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    }
}

/// The world transform at time 0 of a node placed `here` below `parent`: the static
/// chain's, or a moving node's from `rest_world` (one per vrao node in `nodes`, filled as
/// the walk first reaches each: parents come before their children).
fn world_at_rest(nodes: &[Node], rest_world: &mut Vec<DMat4>, parent: &Parent, here: &Parent) -> DMat4 {
    match here.node {
        None => here.world,
        Some(k) if k == rest_world.len() => {
            let local = nodes[k].local_at(0.0);
            let world = parent.node.map_or(local, |p| rest_world[p] * local);
            rest_world.push(world);
            world
        }
        Some(k) => rest_world[k],
    }
}

impl Loader<'_> {
    fn error(&self, message: impl Into<String>) -> Error {
        Error::in_file(self.path, message)
    }

    fn build(&mut self) -> Result<Content> {
        let document = self.document;
        let tracks = self.animation_tracks()?;
        let roots = scene_roots(document);
        if document.skins().next().is_some() {
            self.warnings.ignored.insert("skins (drawn in the bind pose)");
        }

        let mut content = Content {
            meshes: Vec::new(),
            materials: Vec::new(),
            nodes: Vec::new(),
            lights: Vec::new(),
            camera: None,
            warnings: Vec::new(),
        };
        let mut visited = vec![false; document.nodes().len()];
        // Each node with its parent's frame and whether a node above (or it) is scaled
        // below SCALE_MIN on its own (`warn_hidden_nodes` names those).
        let mut stack: Vec<(::gltf::Node, Parent, bool)> =
            roots.into_iter().rev().map(|n| (n, Parent { world: DMat4::IDENTITY, node: None }, false)).collect();
        // The world transform of every vrao node at time 0, for lights and the camera.
        let mut node_rest_world: Vec<DMat4> = Vec::new();
        // Static mesh nodes too small in the world to draw, with why.
        let mut too_small: Vec<(usize, String)> = Vec::new();
        while let Some((node, parent, tiny_above)) = stack.pop() {
            let index = node.index();
            if std::mem::replace(&mut visited[index], true) {
                return Err(self.error(format!("node {index} is reached twice (a cycle, or a node with two parents)")));
            }
            let tiny = tiny_above || is_tiny(&node, tracks.get(&index));
            let here = self.node_frame(&node, &parent, tracks.get(&index), &mut content.nodes)?;
            let world_at_rest = world_at_rest(&content.nodes, &mut node_rest_world, &parent, &here);
            let before = content.meshes.len();
            self.attach(&node, &here, &world_at_rest, &mut content)?;
            // Scales that are each fine can multiply to nothing (1e-3 three times), and
            // positions can be tiny at any scale: judged on the mesh in the world, after
            // the whole chain of transforms. Moving meshes are left out (their scale may
            // animate).
            if here.node.is_none() && !tiny {
                if let Some(why) = too_small_to_draw(&content.meshes[before..]) {
                    too_small.push((index, why));
                }
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, here, tiny));
            }
        }
        self.warn_too_small(&too_small);
        // Nodes without meshes below them are kept: cheap, and their indices stay simple.
        content.materials = std::mem::take(&mut self.materials);
        if content.meshes.is_empty() {
            return Err(self.error("contains no triangles (no mesh in the default scene)"));
        }
        Ok(content)
    }

    /// Where `node` places what hangs below it: folded into the static world transform
    /// while neither it nor an ancestor moves, else a vrao node of its own, pushed onto
    /// `nodes` (`animated`: its tracks, if it moves).
    fn node_frame(
        &self,
        node: &::gltf::Node,
        parent: &Parent,
        animated: Option<&NodeTracks>,
        nodes: &mut Vec<Node>,
    ) -> Result<Parent> {
        let index = node.index();
        let local = self.local_transform(node)?;
        if parent.node.is_none() && animated.is_none() {
            return Ok(Parent { world: parent.world * local.matrix(), node: None });
        }
        let (base, rest) = match (parent.node, local) {
            // A moving root: its static ancestors fold into its base.
            (None, local) => (parent.world, local.trs()),
            (Some(_), Local::Matrix(m)) => (m, Trs::IDENTITY),
            (Some(_), Local::Trs(trs)) => (DMat4::IDENTITY, trs),
        };
        nodes.push(Node {
            name: node.name().map_or_else(|| format!("node {index}"), str::to_string),
            parent: parent.node,
            base,
            rest,
            tracks: animated.cloned().unwrap_or_default(),
        });
        Ok(Parent { world: parent.world, node: Some(nodes.len() - 1) })
    }

    /// What a node carries, placed `here`: its mesh, its light (at its world transform at
    /// time 0) and, for the first camera, the head pose.
    fn attach(
        &mut self,
        node: &::gltf::Node,
        here: &Parent,
        world_at_rest: &DMat4,
        content: &mut Content,
    ) -> Result<()> {
        if let Some(mesh) = node.mesh() {
            self.place_mesh(&mesh, here, &mut content.meshes)?;
        }
        if let Some(light) = node.light() {
            if light.range().is_some() {
                self.warnings.ignored.insert("light range (inverse-square falloff everywhere)");
            }
            content.lights.push(self.light(&light, world_at_rest)?);
        }
        if node.camera().is_some() && content.camera.is_none() {
            let (_, rotation, translation) = world_at_rest.to_scale_rotation_translation();
            if translation.is_finite() && rotation.is_finite() {
                content.camera = Some(HeadPose { position: translation, orientation: rotation.normalize() });
            }
        }
        Ok(())
    }

    /// A node's local transform, checked finite and within the bounds static values have
    /// (`limits.rs`): a translation beyond 10⁶ m or a scale above 10⁶ is refused naming the
    /// node. A scale below 10⁻⁶ (0 included: glTF content hides nodes so) is kept: what
    /// hangs below collapses and is not drawn, and [`Loader::warn_hidden_nodes`] says so.
    fn local_transform(&self, node: &::gltf::Node) -> Result<Local> {
        let local = match node.transform() {
            ::gltf::scene::Transform::Matrix { matrix } => {
                Local::Matrix(DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))))
            }
            ::gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
                let [x, y, z, w] = rotation.map(f64::from);
                let q = DQuat::from_xyzw(x, y, z, w);
                if q.length().is_nan() || q.length() <= 1e-6 {
                    return Err(self.error(format!("node {}: rotation {rotation:?} is not a quaternion", node.index())));
                }
                Local::Trs(Trs {
                    translation: DVec3::from(translation.map(f64::from)),
                    rotation: q.normalize(),
                    scale: DVec3::from(scale.map(f64::from)),
                })
            }
        };
        if !local.matrix().is_finite() {
            return Err(self.error(format!("node {}: transform is not finite", node.index())));
        }
        let (translation, scale) = match local {
            Local::Trs(trs) => (trs.translation, trs.scale.abs()),
            Local::Matrix(m) => (m.w_axis.truncate(), matrix_scale(&m)),
        };
        use super::limits::{coordinate_trouble, shortest, SCALE_MAX};
        let far = translation.to_array().into_iter().find_map(|t| coordinate_trouble("translation", t));
        let large = (scale.max_element() > SCALE_MAX)
            .then(|| format!("scale {} is larger than {SCALE_MAX:e}", shortest(scale.max_element())));
        match far.or(large) {
            Some(trouble) => Err(self.error(format!("node {}: {trouble}", node.index()))),
            None => Ok(local),
        }
    }

    /// One warning line naming the nodes whose scale is below [`super::limits::SCALE_MIN`] (0 included)
    /// with meshes at or below them and no scale animation: those meshes collapse and are
    /// not drawn (glTF content hides nodes with scale 0, so the file is not refused).
    fn warn_hidden_nodes(&self, tracks: &HashMap<usize, NodeTracks>) {
        use super::limits::SCALE_MIN;
        let nodes: Vec<::gltf::Node> = self.document.nodes().collect();
        let hidden: Vec<usize> =
            nodes.iter().filter(|n| is_tiny(n, tracks.get(&n.index()))).map(|n| n.index()).collect();
        if hidden.is_empty() {
            return;
        }
        // Whether some mesh hangs at or below each node (post-order; a cycle, refused
        // later, ends the walk).
        let mut below = vec![false; nodes.len()];
        let mut state = vec![0u8; nodes.len()];
        for &start in &hidden {
            let mut stack = vec![(start, false)];
            while let Some((i, done)) = stack.pop() {
                if done {
                    below[i] = nodes[i].mesh().is_some() || nodes[i].children().any(|c| below[c.index()]);
                    state[i] = 2;
                } else if state[i] == 0 {
                    state[i] = 1;
                    stack.push((i, true));
                    stack.extend(nodes[i].children().map(|c| (c.index(), false)).filter(|&(c, _)| state[c] == 0));
                }
            }
        }
        let named: Vec<String> = hidden.iter().filter(|&&i| below[i]).map(|i| i.to_string()).collect();
        if named.is_empty() {
            return;
        }
        let more = if named.len() > 8 { format!(" and {} more", named.len() - 8) } else { String::new() };
        log::warn!(
            "{}: node{} {}{more} scaled below {SCALE_MIN:e}: the meshes below {} are not drawn",
            self.path.display(),
            if named.len() == 1 { "" } else { "s" },
            named[..named.len().min(8)].join(", "),
            if named.len() == 1 { "it" } else { "them" }
        );
    }

    /// One warning line naming the static mesh nodes `too_small` lists (node, why) that
    /// no single node's scale hides ([`Loader::warn_hidden_nodes`]) but whose world
    /// transform or positions leave their meshes under [`super::limits::SCALE_MIN`] metres.
    fn warn_too_small(&self, too_small: &[(usize, String)]) {
        use super::limits::SCALE_MIN;
        if too_small.is_empty() {
            return;
        }
        let named: Vec<String> = too_small.iter().take(8).map(|(node, why)| format!("{node} ({why})")).collect();
        let more = if too_small.len() > 8 { format!(" and {} more", too_small.len() - 8) } else { String::new() };
        log::warn!(
            "{}: node{} {}{more} smaller than {SCALE_MIN:e} m in the world (the scales of the nodes above \
             multiplied, or the positions): the meshes are not drawn",
            self.path.display(),
            if too_small.len() == 1 { "" } else { "s" },
            named.join(", "),
        );
    }

    /// The mesh's primitives placed by `at`: baked into world space when static, in the
    /// node's frame when it moves.
    fn place_mesh(&mut self, mesh: &::gltf::Mesh, at: &Parent, out: &mut Vec<Mesh>) -> Result<()> {
        if !self.primitives.contains_key(&mesh.index()) {
            let decoded = self.decode_mesh(mesh)?;
            self.primitives.insert(mesh.index(), decoded);
        }
        for primitive in &self.primitives[&mesh.index()] {
            let g = &primitive.geometry;
            // Nothing to draw (an OBJ object without faces is dropped the same way).
            if g.indices.is_empty() {
                continue;
            }
            let more = super::limits::GeometryBudget {
                triangles: g.indices.len() / 3,
                vertices: g.positions.len(),
                meshes: 1,
            };
            self.budget = self.budget.plus(more, &format!("mesh '{}'", primitive.name)).map_err(|m| self.error(m))?;
            let material = self.material_offset + primitive.material;
            out.push(match at.node {
                Some(node) => {
                    let points: Vec<DVec3> = g.positions.iter().map(|p| p.as_dvec3()).collect();
                    let (origin, positions) = Mesh::recentre(&points);
                    Mesh {
                        colors: primitive.extras.colors.clone(),
                        tangents: primitive.extras.tangents.clone(),
                        uvs1: primitive.extras.uvs1.clone(),
                        name: primitive.name.clone(),
                        origin,
                        positions,
                        normals: g.normals.clone(),
                        uvs: g.uvs.clone(),
                        indices: g.indices.clone(),
                        material,
                        node: Some(node),
                    }
                }
                None => bake_static(primitive, &at.world, material),
            });
        }
        Ok(())
    }

    /// Every primitive of a mesh in its local frame, with normals.
    fn decode_mesh(&mut self, mesh: &::gltf::Mesh) -> Result<Vec<LocalPrimitive>> {
        let mesh_name = mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), |n| format!("mesh '{n}'"));
        let mut out = Vec::new();
        for primitive in mesh.primitives() {
            let what = format!("{mesh_name} primitive {}", primitive.index());
            let mode = primitive.mode();
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                // Points and lines have no surface to occlude or be occluded: the rest of
                // the file is drawn.
                self.warnings.ignored.insert("points and lines primitives (vrao draws triangles)");
                continue;
            }
            if primitive.morph_targets().next().is_some() {
                self.warnings.ignored.insert("morph targets (drawn in the bind pose)");
            }
            let attributes = self.read_attributes(&primitive, &what)?;
            let (geometry, mut extras) = self.with_normals(&primitive, attributes, &what)?;
            // A tangent along the normal leaves no direction once the shader takes the
            // normal out of it (noise, seen as stripes): the whole primitive then uses the
            // frame derived from its texture coordinates, as it does without TANGENT
            // (mixing the two would seam where they meet).
            if let Some(vertex) = degenerate_tangent(&extras.tangents, &geometry.normals) {
                extras.tangents.clear();
                self.warnings.derived_tangents.push(format!("{what} (vertex {vertex})"));
            }
            let material = self.material(&primitive.material())?;
            let name = match mesh.primitives().len() {
                1 => mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string),
                _ => format!("{}.{}", mesh.name().unwrap_or("mesh"), primitive.index()),
            };
            out.push(LocalPrimitive { name, geometry, extras, material });
        }
        Ok(out)
    }

    /// A triangle primitive's vertex attributes other than normals, and its triangle list,
    /// each checked against the positions' count.
    fn read_attributes(&mut self, primitive: &::gltf::Primitive, what: &str) -> Result<Attributes> {
        let position = primitive
            .get(&::gltf::Semantic::Positions)
            .ok_or_else(|| self.error(format!("{what} has no POSITION attribute")))?;
        let positions: Vec<Vec3> = self
            .read_as::<3>(&position, Use::Position, &format!("{what} POSITION"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        let count = positions.len();
        let indices: Vec<u32> = match primitive.indices() {
            Some(accessor) => self.read_indices(&accessor, count, &format!("{what} indices"))?,
            None => (0..count as u32).collect(),
        };
        let indices = triangle_list(primitive.mode(), indices);
        if !indices.len().is_multiple_of(3) {
            return Err(self.error(format!("{what}: {} indices, not a whole number of triangles", indices.len())));
        }
        let uvs = self.read_texcoords(primitive, 0, count, what)?;
        let uvs1 = self.read_texcoords(primitive, 1, count, what)?;
        if primitive.get(&::gltf::Semantic::TexCoords(2)).is_some() {
            self.warnings.ignored.insert("texture coordinate sets beyond 1");
        }
        let colors = match primitive.get(&::gltf::Semantic::Colors(0)) {
            Some(accessor) => self.read_colors(&accessor, &format!("{what} COLOR_0"), count)?,
            None => Vec::new(),
        };
        let tangents: Vec<Vec4> = match primitive.get(&::gltf::Semantic::Tangents) {
            Some(accessor) => {
                let label = format!("{what} TANGENT");
                let tangents = self.read_as::<4>(&accessor, Use::Tangent, &label)?;
                self.same_count(tangents.len(), count, &label)?;
                tangents.into_iter().map(Vec4::from).collect()
            }
            None => Vec::new(),
        };
        Ok(Attributes { positions, indices, uvs, uvs1, colors, tangents })
    }

    /// TEXCOORD_`set`, one per position, or empty when the primitive has none.
    fn read_texcoords(&self, primitive: &::gltf::Primitive, set: u32, count: usize, what: &str) -> Result<Vec<Vec2>> {
        let Some(accessor) = primitive.get(&::gltf::Semantic::TexCoords(set)) else { return Ok(Vec::new()) };
        let label = format!("{what} TEXCOORD_{set}");
        let uvs = self.read_as::<2>(&accessor, Use::TexCoord, &label)?;
        self.same_count(uvs.len(), count, &label)?;
        Ok(uvs.into_iter().map(Vec2::from).collect())
    }

    /// The primitive's geometry with its NORMAL (unit, the broken ones repaired), or with
    /// normals computed at creases; the second uvs, colours and tangents then follow the
    /// vertices the creases split.
    fn with_normals(
        &self,
        primitive: &::gltf::Primitive,
        attributes: Attributes,
        what: &str,
    ) -> Result<(Geometry, VertexExtras)> {
        let Attributes { positions, indices, uvs, uvs1, colors, tangents } = attributes;
        let count = positions.len();
        match primitive.get(&::gltf::Semantic::Normals) {
            Some(accessor) => {
                let label = format!("{what} NORMAL");
                let mut normals: Vec<Vec3> =
                    self.read_as::<3>(&accessor, Use::Normal, &label)?.into_iter().map(Vec3::from).collect();
                self.same_count(normals.len(), count, &label)?;
                keep_unit_repair_others(&positions, &mut normals, &indices);
                let uvs = if uvs.is_empty() { vec![Vec2::ZERO; count] } else { uvs };
                Ok((Geometry { positions, normals, uvs, indices }, VertexExtras { uvs1, colors, tangents }))
            }
            None => {
                // Computed normals split vertices at creases: colours and tangents follow.
                let (geometry, sources) =
                    normals::compute_normals_with_sources(&positions, &uvs, &indices, normals::DEFAULT_CREASE_DEG);
                let extras = VertexExtras {
                    uvs1: follow(&sources, &uvs1),
                    colors: follow(&sources, &colors),
                    tangents: follow(&sources, &tangents),
                };
                Ok((geometry, extras))
            }
        }
    }

    /// COLOR_0 as linear RGBA (VEC3 gets alpha 1), one per vertex.
    fn read_colors(&self, accessor: &::gltf::Accessor, what: &str, count: usize) -> Result<Vec<Vec4>> {
        let colors: Vec<Vec4> = match accessor.dimensions() {
            ::gltf::accessor::Dimensions::Vec3 => {
                self.read_as::<3>(accessor, Use::Color, what)?.into_iter().map(|c| Vec3::from(c).extend(1.0)).collect()
            }
            _ => self.read_as::<4>(accessor, Use::Color, what)?.into_iter().map(Vec4::from).collect(),
        };
        self.same_count(colors.len(), count, what)?;
        // Colours are reflectance factors: outside [0, 1] they would add light.
        Ok(colors.into_iter().map(|c| c.clamp(Vec4::ZERO, Vec4::ONE)).collect())
    }

    fn same_count(&self, found: usize, expected: usize, what: &str) -> Result<()> {
        if found != expected {
            return Err(self.error(format!("{what} has {found} elements, POSITION has {expected}")));
        }
        Ok(())
    }

    /// The vrao material for a glTF material, made on first use.
    fn material(&mut self, material: &::gltf::Material) -> Result<usize> {
        if let Some(&i) = self.material_of.get(&material.index()) {
            return Ok(i);
        }
        let name = match material.index() {
            Some(i) => material.name().map_or_else(|| format!("material {i}"), str::to_string),
            None => "default".to_string(),
        };
        let pbr = material.pbr_metallic_roughness();
        // The default material's metallicFactor is 1 by the spec, not by the file: no warning.
        let authored = material.index().is_some();
        if authored && (pbr.metallic_factor() > 0.0 || pbr.metallic_roughness_texture().is_some()) {
            self.warnings.ignored.insert("metallic-roughness (vrao shades the base colour as diffuse)");
        }
        let factor = pbr.base_color_factor();
        let emissive = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
        if !factor.iter().all(|c| c.is_finite()) || !emissive.is_finite() || emissive.min_element() < 0.0 {
            return Err(self.error(format!("material '{name}': colour factors must be finite and not negative")));
        }
        let alpha_mode = self.alpha_mode(material, &name)?;
        let diffuse_texture = match pbr.base_color_texture() {
            Some(info) => Some(self.texture(&info.texture(), placement_of_info(&info), &name)?),
            None => None,
        };
        let emissive_texture = match material.emissive_texture() {
            Some(info) => Some(self.texture(&info.texture(), placement_of_info(&info), &name)?),
            None => None,
        };
        let normal_texture = self.normal_texture(material, &name)?;
        let occlusion_texture = self.occlusion_texture(material, &name)?;
        self.materials.push(Material {
            name,
            diffuse: Vec3::new(factor[0], factor[1], factor[2]).clamp(Vec3::ZERO, Vec3::ONE),
            emissive,
            diffuse_texture,
            emissive_texture,
            normal_texture,
            occlusion_texture,
            alpha: factor[3].clamp(0.0, 1.0),
            alpha_mode,
            double_sided: material.double_sided(),
        });
        let i = self.materials.len() - 1;
        self.material_of.insert(material.index(), i);
        Ok(i)
    }

    /// A material's alpha mode; a mask's cutoff must lie in [0, 1].
    fn alpha_mode(&self, material: &::gltf::Material, name: &str) -> Result<AlphaMode> {
        Ok(match material.alpha_mode() {
            ::gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            ::gltf::material::AlphaMode::Mask => {
                let cutoff = material.alpha_cutoff().unwrap_or(0.5);
                if !(0.0..=1.0).contains(&cutoff) {
                    return Err(self.error(format!("material '{name}': alphaCutoff {cutoff} is not in [0, 1]")));
                }
                AlphaMode::Mask { cutoff }
            }
            ::gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        })
    }

    /// A material's normal map and its scale (finite), if it has one.
    fn normal_texture(&mut self, material: &::gltf::Material, name: &str) -> Result<Option<(Texture, f32)>> {
        let Some(normal) = material.normal_texture() else { return Ok(None) };
        let placement =
            placement_of_extension(normal.extension_value("KHR_texture_transform"), normal.tex_coord(), name)
                .map_err(|m| self.error(m))?;
        let scale = normal.scale();
        if !scale.is_finite() {
            return Err(self.error(format!("material '{name}': normalTexture scale {scale} is not finite")));
        }
        Ok(Some((self.texture(&normal.texture(), Ok(placement), name)?, scale)))
    }

    /// A material's occlusion map and its strength (in [0, 1]), if it has one.
    fn occlusion_texture(&mut self, material: &::gltf::Material, name: &str) -> Result<Option<(Texture, f32)>> {
        let Some(occlusion) = material.occlusion_texture() else { return Ok(None) };
        let placement =
            placement_of_extension(occlusion.extension_value("KHR_texture_transform"), occlusion.tex_coord(), name)
                .map_err(|m| self.error(m))?;
        let strength = occlusion.strength();
        if !(0.0..=1.0).contains(&strength) {
            return Err(self.error(format!("material '{name}': occlusionTexture strength {strength} is not in [0, 1]")));
        }
        Ok(Some((self.texture(&occlusion.texture(), Ok(placement), name)?, strength)))
    }

    /// A material's texture: its image (decoded once), its sampler and where it is placed
    /// (`KHR_texture_transform`).
    fn texture(
        &mut self,
        texture: &::gltf::Texture,
        placement: std::result::Result<Placement, super::limits::Trouble>,
        material: &str,
    ) -> Result<Texture> {
        let placement = placement.map_err(|m| self.error(m))?;
        let mut image = self.image(&texture.source())?;
        image.sampling = sampling_of(&texture.sampler(), placement.transform);
        image.sampling.tex_coord = match placement.tex_coord {
            0 | 1 => placement.tex_coord,
            _ => {
                self.warnings.ignored.insert("texture coordinate sets beyond 1");
                0
            }
        };
        if !image.sampling.transform.is_finite() {
            return Err(self.error(format!("material '{material}': KHR_texture_transform is not finite")));
        }
        Ok(image)
    }

    /// A decoded image (PNG, JPEG, ... by content), once per source, within the scene's
    /// texture budget.
    fn image(&mut self, image: &::gltf::Image) -> Result<Texture> {
        let index = image.index();
        let source = match image.source() {
            ::gltf::image::Source::View { view, .. } => ImageSource::View(view.index()),
            ::gltf::image::Source::Uri { uri, .. } => ImageSource::Uri(uri.to_string()),
        };
        if let Some(t) = self.images.get(&source) {
            return Ok(t.clone());
        }
        let what = format!("image {index}");
        let bytes: Vec<u8> = match image.source() {
            // Checked against its buffer in checked arithmetic (a byteOffset near 2⁶⁴ is
            // refused, not wrapped); `precheck` saw to the mimeType the crate unwraps.
            ::gltf::image::Source::View { view, .. } => self.view_bytes(&view, &what)?.to_vec(),
            ::gltf::image::Source::Uri { uri, .. } => {
                resolve_uri(self.path, uri).map_err(|m| self.error(format!("{what}: {m}")))?
            }
        };
        let texture = decode_image(&bytes).map_err(|Problem(m)| self.error(format!("{what}: {m}")))?;
        self.texture_bytes += texture.rgba8.len() as u64;
        if let Some(trouble) = super::limits::texture_budget_trouble(&what, self.texture_bytes) {
            return Err(self.error(trouble));
        }
        self.images.insert(source, texture.clone());
        Ok(texture)
    }

    /// A punctual light at its node's world transform (lights shine along the node's −Z).
    fn light(&self, light: &::gltf::khr_lights_punctual::Light, world: &DMat4) -> Result<Light> {
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        if !color.is_finite() || color.min_element() < 0.0 || !intensity.is_finite() || intensity < 0.0 {
            return Err(
                self.error(format!("light {}: colour and intensity must be finite and not negative", light.index()))
            );
        }
        let position = world.transform_point3(DVec3::ZERO);
        let direction = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero().as_vec3();
        if direction == Vec3::ZERO && !matches!(light.kind(), ::gltf::khr_lights_punctual::Kind::Point) {
            return Err(self.error(format!("light {}: its node's transform gives it no direction", light.index())));
        }
        Ok(match light.kind() {
            ::gltf::khr_lights_punctual::Kind::Directional => Light::Directional { direction, color, intensity },
            ::gltf::khr_lights_punctual::Kind::Point => Light::Point { position, color, intensity },
            ::gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let right = std::f32::consts::FRAC_PI_2;
                if !(0.0..right).contains(&inner_cone_angle)
                    || !(inner_cone_angle..=right).contains(&outer_cone_angle)
                    || outer_cone_angle <= inner_cone_angle
                {
                    return Err(self.error(format!(
                        "light {}: spot cone angles {inner_cone_angle}, {outer_cone_angle} need 0 <= inner < outer <= pi/2",
                        light.index()
                    )));
                }
                Light::Spot {
                    position,
                    direction,
                    color,
                    intensity,
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                }
            }
        })
    }

    /// The translation, rotation and scale tracks of every animated node. When several
    /// animations drive the same property, the first one's track is kept.
    fn animation_tracks(&mut self) -> Result<HashMap<usize, NodeTracks>> {
        let mut tracks: HashMap<usize, NodeTracks> = HashMap::new();
        let mut keys = 0usize;
        for animation in self.document.animations() {
            for channel in animation.channels() {
                let what = format!("animation {} channel {}", animation.index(), channel.index());
                let sampler = channel.sampler();
                let interpolation = match sampler.interpolation() {
                    ::gltf::animation::Interpolation::Step => Interpolation::Step,
                    ::gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    ::gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let property = channel.target().property();
                if property == ::gltf::animation::Property::MorphTargetWeights {
                    self.warnings.ignored.insert("morph target weight animations");
                    continue;
                }
                let times = self.read_scalars(&sampler.input(), &format!("{what} input"))?;
                keys += times.len();
                if keys > MAX_KEYS {
                    return Err(self.error(format!("more than {MAX_KEYS} animation keys (vrao's limit)")));
                }
                if times.is_empty() {
                    return Err(self.error(format!("{what}: no keys")));
                }
                if let Some(t) = times.iter().find(|t| **t < 0.0) {
                    return Err(self.error(format!("{what}: key time {t} is negative")));
                }
                if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
                    return Err(self.error(format!("{what}: key times {} then {} are not increasing", w[0], w[1])));
                }
                let stride = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
                let output = sampler.output();
                let label = format!("{what} output");
                let expected = times.len() * stride;
                let node = tracks.entry(channel.target().node().index()).or_default();
                let mismatch =
                    |found: usize| format!("{label}: {found} values for {} keys (expected {expected})", times.len());
                match property {
                    ::gltf::animation::Property::Rotation => {
                        let values = self.read_as::<4>(&output, Use::Rotation, &label)?;
                        if values.len() != expected {
                            return Err(Error::in_file(self.path, mismatch(values.len())));
                        }
                        let values = values
                            .into_iter()
                            .map(|[x, y, z, w]| DQuat::from_xyzw(x as f64, y as f64, z as f64, w as f64))
                            .collect();
                        node.rotation.get_or_insert(Track { interpolation, times, values });
                    }
                    _ => {
                        let values = self.read_as::<3>(&output, Use::KeyVectors, &label)?;
                        if values.len() != expected {
                            return Err(Error::in_file(self.path, mismatch(values.len())));
                        }
                        let values: Vec<DVec3> = values.into_iter().map(|v| Vec3::from(v).as_dvec3()).collect();
                        let translation = property == ::gltf::animation::Property::Translation;
                        if let Some(trouble) = key_trouble(&values, stride, translation) {
                            return Err(self.error(format!("{label}: {trouble}")));
                        }
                        let track = Track { interpolation, times, values };
                        if translation {
                            node.translation.get_or_insert(track);
                        } else {
                            node.scale.get_or_insert(track);
                        }
                    }
                }
            }
        }
        tracks.retain(|_, t| !t.is_empty());
        self.warn_hidden_nodes(&tracks);
        Ok(tracks)
    }
}

/// The sine of the angle under which a TANGENT counts as parallel to its vertex's normal:
/// 0.01 (0.57°). Authored tangents are orthogonal to the normal (MikkTSpace makes them
/// so) or near it; one this close leaves, after the shader removes the normal's part,
/// a remainder of the size of the 16-bit vertex quantisation.
const TANGENT_PARALLEL_SINE: f32 = 0.01;

/// The first vertex whose tangent (xyz of `tangents`, one per vertex of `normals`) is zero,
/// not finite, or parallel to its unit normal within [`TANGENT_PARALLEL_SINE`]; `None`
/// when every one gives a direction (or there are no tangents).
fn degenerate_tangent(tangents: &[Vec4], normals: &[Vec3]) -> Option<usize> {
    tangents.iter().zip(normals).position(|(t, n)| {
        let t = t.truncate();
        let length = t.length();
        let across = (t - *n * n.dot(t)).length();
        !(length.is_finite() && length > 1e-6 && across > TANGENT_PARALLEL_SINE * length)
    })
}

/// `values` (one per source vertex, or empty) for the vertices made from `sources`.
fn follow<T: Copy>(sources: &[u32], values: &[T]) -> Vec<T> {
    if values.is_empty() {
        return Vec::new();
    }
    sources.iter().map(|&v| values[v as usize]).collect()
}

/// Whether `node`'s own scale is below [`super::limits::SCALE_MIN`] on some axis (0
/// included) and not animated (`tracks`): what hangs below it collapses.
fn is_tiny(node: &::gltf::Node, tracks: Option<&NodeTracks>) -> bool {
    let scale = match node.transform() {
        ::gltf::scene::Transform::Matrix { matrix } => {
            matrix_scale(&DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))))
        }
        ::gltf::scene::Transform::Decomposed { scale, .. } => DVec3::from(scale.map(f64::from)).abs(),
    };
    scale.min_element() < super::limits::SCALE_MIN && tracks.is_none_or(|t| t.scale.is_none())
}

/// Why `meshes`, baked into world space, are too small to draw, or `None`: their largest
/// side under [`super::limits::SCALE_MIN`] metres (1 µm: not a pixel at any framing vrao
/// gives), whether the nodes' scales multiplied down to it or the positions are tiny. A
/// mesh flattened on one axis keeps its other sides and is drawn.
fn too_small_to_draw(meshes: &[Mesh]) -> Option<String> {
    use super::limits::SCALE_MIN;
    if meshes.is_empty() {
        return None;
    }
    let mut bounds = super::Aabb::EMPTY;
    meshes.iter().flat_map(|m| m.positions.iter()).for_each(|p| bounds.extend(p.as_dvec3()));
    let size = if bounds.is_empty() { 0.0 } else { bounds.size().max_element() };
    // Two digits: the size comes out of f32 positions (1e-9 reads 1.0000002e-9).
    (size < SCALE_MIN).then(|| format!("{size:.1e} m across"))
}

/// The size of each axis of a matrix's linear part (its columns' lengths).
fn matrix_scale(m: &DMat4) -> DVec3 {
    DVec3::new(m.x_axis.truncate().length(), m.y_axis.truncate().length(), m.z_axis.truncate().length())
}

/// One-line trouble for the first translation or scale key (or cubic-spline tangent) of an
/// animation output beyond the bounds static values have (`limits.rs`): a translation
/// beyond 10⁶ m, a scale above 10⁶, or a scale key below 10⁻⁶ that is not 0 (a key of 0
/// hides the node while it holds). `stride` is 3 for cubic splines (in-tangent, value,
/// out-tangent), else 1.
fn key_trouble(values: &[DVec3], stride: usize, translation: bool) -> Option<String> {
    use super::limits::{coordinate_trouble, key_scale_trouble, shortest, SCALE_MAX};
    values.iter().enumerate().find_map(|(i, v)| {
        let (key, role) = (i / stride + 1, i % stride);
        let tangent = stride == 3 && role != 1;
        let what = match (tangent, role) {
            (false, _) => format!("key {key}"),
            (true, 0) => format!("key {key} in-tangent"),
            (true, _) => format!("key {key} out-tangent"),
        };
        v.to_array().into_iter().find_map(|c| {
            if translation {
                coordinate_trouble(&format!("{what} translation"), c)
            } else if tangent {
                (c.abs() > SCALE_MAX).then(|| format!("{what} scale {} is larger than {SCALE_MAX:e}", shortest(c)))
            } else {
                key_scale_trouble(&format!("{what} scale"), c)
            }
        })
    })
}

/// A node's local transform as the file gives it.
#[derive(Clone, Copy)]
enum Local {
    Matrix(DMat4),
    Trs(Trs),
}

impl Local {
    fn matrix(&self) -> DMat4 {
        match self {
            Local::Matrix(m) => *m,
            Local::Trs(trs) => trs.matrix(),
        }
    }
    /// As a TRS (a matrix decomposed; glTF forbids animating matrix nodes, so this only
    /// serves a file that does it anyway).
    fn trs(&self) -> Trs {
        match self {
            Local::Trs(trs) => *trs,
            Local::Matrix(m) => {
                let (scale, rotation, translation) = m.to_scale_rotation_translation();
                Trs { translation, rotation, scale }
            }
        }
    }
}

/// Where a texture reads the mesh's texture coordinates: which set and through which
/// `KHR_texture_transform`.
struct Placement {
    tex_coord: u32,
    transform: glam::Affine2,
}

/// A base-colour or emissive texture's placement (`textureInfo`).
fn placement_of_info(info: &::gltf::texture::Info) -> std::result::Result<Placement, super::limits::Trouble> {
    Ok(match info.texture_transform() {
        Some(t) => Placement {
            tex_coord: t.tex_coord().unwrap_or(info.tex_coord()),
            transform: super::uv_transform(t.offset().into(), t.rotation(), t.scale().into()),
        },
        None => Placement { tex_coord: info.tex_coord(), transform: glam::Affine2::IDENTITY },
    })
}

/// A normal or occlusion texture's placement: the crate exposes their
/// `KHR_texture_transform` only as JSON.
fn placement_of_extension(
    extension: Option<&json::Value>,
    tex_coord: u32,
    material: &str,
) -> std::result::Result<Placement, super::limits::Trouble> {
    let Some(extension) = extension else {
        return Ok(Placement { tex_coord, transform: glam::Affine2::IDENTITY });
    };
    let bad =
        || format!("material '{material}': KHR_texture_transform {extension} is not offset/rotation/scale numbers");
    let pair = |key: &str, default: [f32; 2]| -> std::result::Result<glam::Vec2, super::limits::Trouble> {
        match extension.get(key) {
            None => Ok(default.into()),
            Some(json::Value::Array(v)) if v.len() == 2 => {
                let c: Vec<f32> = v.iter().filter_map(|x| x.as_f64()).map(|x| x as f32).collect();
                if c.len() == 2 {
                    Ok(glam::Vec2::new(c[0], c[1]))
                } else {
                    Err(bad().into())
                }
            }
            _ => Err(bad().into()),
        }
    };
    let rotation = match extension.get("rotation") {
        None => 0.0,
        Some(r) => r.as_f64().ok_or_else(bad)? as f32,
    };
    let tex_coord = match extension.get("texCoord") {
        None => tex_coord,
        Some(t) => t.as_u64().and_then(|t| u32::try_from(t).ok()).ok_or_else(bad)?,
    };
    let transform = super::uv_transform(pair("offset", [0.0, 0.0])?, rotation, pair("scale", [1.0, 1.0])?);
    Ok(Placement { tex_coord, transform })
}

/// glTF's sampler as vrao's: wrap per axis (repeat when unset), filters (linear when
/// unset, with linear mipmaps, as engines pick).
fn sampling_of(sampler: &::gltf::texture::Sampler, transform: glam::Affine2) -> super::Sampling {
    use super::{Filter, Wrap};
    use ::gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |mode| match mode {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    let magnify = match sampler.mag_filter() {
        Some(MagFilter::Nearest) => Filter::Nearest,
        _ => Filter::Linear,
    };
    let (minify, mipmaps) = match sampler.min_filter() {
        Some(MinFilter::Nearest) => (Filter::Nearest, None),
        Some(MinFilter::Linear) => (Filter::Linear, None),
        Some(MinFilter::NearestMipmapNearest) => (Filter::Nearest, Some(Filter::Nearest)),
        Some(MinFilter::LinearMipmapNearest) => (Filter::Linear, Some(Filter::Nearest)),
        Some(MinFilter::NearestMipmapLinear) => (Filter::Nearest, Some(Filter::Linear)),
        Some(MinFilter::LinearMipmapLinear) | None => (Filter::Linear, Some(Filter::Linear)),
    };
    super::Sampling {
        wrap_u: wrap(sampler.wrap_s()),
        wrap_v: wrap(sampler.wrap_t()),
        magnify,
        minify,
        mipmaps,
        transform,
        tex_coord: 0,
    }
}

/// Decodes an image to RGBA8, refusing sides over [`MAX_TEXTURE_SIDE`] before decoding.
fn decode_image(bytes: &[u8]) -> std::result::Result<Texture, Problem> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot decode: {e}"))?;
    let (width, height) = reader.into_dimensions().map_err(|e| format!("cannot decode: {e}"))?;
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE || width == 0 || height == 0 {
        return Err(Problem(format!("{width}×{height} texels; vrao takes sides of 1 to {MAX_TEXTURE_SIDE}")));
    }
    let image = super::limits::decode_texture(bytes).map_err(|e| format!("cannot decode: {e}"))?.into_rgba8();
    Ok(Texture {
        sampling: Default::default(),
        width: image.width(),
        height: image.height(),
        rgba8: image.into_raw().into(),
        source: None,
    })
}

/// Normals as [`normals::repair_normals`] leaves them, except that a normal already of
/// unit length keeps its exact bits (normalising again may move the last bit, and a file
/// written from a loaded OBJ should give that OBJ's normals exactly).
fn keep_unit_repair_others(positions: &[Vec3], normals: &mut [Vec3], indices: &[u32]) {
    let is_unit = |n: &Vec3| (n.length_squared() - 1.0).abs() < 1e-6;
    if normals.iter().all(is_unit) {
        return;
    }
    let mut repaired = normals.to_vec();
    normals::repair_normals(positions, &mut repaired, indices);
    for (n, r) in normals.iter_mut().zip(repaired) {
        if !is_unit(n) {
            *n = r;
        }
    }
}

/// A static primitive in world space: positions through `world` in f64 and recentred as
/// the OBJ loader does (so the identity gives the OBJ loader's mesh), normals by the
/// inverse transpose, winding reversed by a mirroring transform.
fn bake_static(primitive: &LocalPrimitive, world: &DMat4, material: usize) -> Mesh {
    let g = &primitive.geometry;
    let identity = *world == DMat4::IDENTITY;
    let points: Vec<DVec3> = g.positions.iter().map(|p| world.transform_point3(p.as_dvec3())).collect();
    let (origin, positions) = Mesh::recentre(&points);
    let mut indices = g.indices.clone();
    let mut normals = g.normals.clone();
    let mut tangents = primitive.extras.tangents.clone();
    if !identity {
        let linear = DMat3::from_mat4(*world);
        let normal_matrix = linear.inverse().transpose();
        normals = normals.iter().map(|n| (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3()).collect();
        tangents = super::transform_tangents(&tangents, linear);
        if linear.determinant() < 0.0 {
            indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
        }
        // A singular transform flattens the mesh; its normals then come from the faces.
        normals::repair_normals(&positions, &mut normals, &indices);
    }
    Mesh {
        name: primitive.name.clone(),
        origin,
        positions,
        normals,
        uvs: g.uvs.clone(),
        uvs1: primitive.extras.uvs1.clone(),
        colors: primitive.extras.colors.clone(),
        tangents,
        indices,
        material,
        node: None,
    }
}

/// A primitive's vertex order as a triangle list: a strip's triangle i is (i, i+1, i+2)
/// for even i and (i, i+2, i+1) for odd i, a fan's (i+1, i+2, 0), as glTF 2.0 §3.7.2.1
/// orders them, so every triangle keeps the strip's or fan's winding.
fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
    let triangles = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..triangles)
            .flat_map(|i| {
                let (a, b) = if i % 2 == 0 { (i + 1, i + 2) } else { (i + 2, i + 1) };
                [indices[i], indices[a], indices[b]]
            })
            .collect(),
        Mode::TriangleFan => (0..triangles).flat_map(|i| [indices[i + 1], indices[i + 2], indices[0]]).collect(),
        _ => indices,
    }
}
