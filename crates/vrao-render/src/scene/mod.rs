//! Scenes: meshes with materials, lights, an optional environment and the head pose.
//!
//! Loaded from OBJ+MTL (`obj.rs`), from a TOML scene file (`file.rs`), or built in
//! (`builtin.rs`, addressed as `builtin:NAME`). Every loader validates what it reads and
//! returns [`vrao_ao::Error::Input`] naming the file and line for anything malformed.

pub mod animation;
pub mod builtin;
pub mod content;
pub mod edge_cases;
pub mod environment;
pub mod file;
pub mod furnished;

#[cfg(feature = "gltf")]
pub mod gltf;
pub mod limits;
pub mod normals;
pub mod obj;
pub mod shell;
pub mod texture;

use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};
use vrao_ao::{Error, HeadPose, Result};

pub use animation::{Interpolation, Node, NodeTracks, Track, Trs};
pub use environment::Environment;
pub use texture::{uv_transform, uv_transform_parts, Filter, Sampling, Texture, Wrap};

/// A triangle mesh. Positions are stored relative to `origin` (f64) so that a scene
/// placed far from the world origin keeps full f32 precision near the camera.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Name from the source file (or the builtin's name).
    pub name: String,
    /// World position (f64) that `positions` are relative to.
    pub origin: DVec3,
    /// Vertex positions relative to `origin`.
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position (zero when the source has none). v = 0 is the
    /// top row of the texture (OBJ's bottom-up v is flipped at load).
    pub uvs: Vec<Vec2>,
    /// The second texture coordinates (glTF `TEXCOORD_1`), one per position, or empty:
    /// a texture that reads set 1 ([`Sampling::tex_coord`]) then reads `uvs`.
    pub uvs1: Vec<Vec2>,
    /// Linear RGBA vertex colours (glTF `COLOR_0`), one per position, multiplying the
    /// material's base colour and alpha; empty when the source has none (white).
    pub colors: Vec<Vec4>,
    /// Tangents for the normal texture (glTF `TANGENT`: xyz along +u, w the bitangent's
    /// sign), one per position; empty when the material has no normal texture.
    pub tangents: Vec<Vec4>,
    /// Triangle list into the vertex arrays.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// The animated node this mesh moves with ([`Scene::nodes`]); `None` for static
    /// geometry, which is in world space. With a node, `origin` and `positions` are in the
    /// node's local frame.
    pub node: Option<usize>,
}

impl Mesh {
    /// Splits world positions into an origin (the bounding-box centre, f64) and f32 offsets
    /// from it, so that geometry far from the world origin keeps its precision.
    pub fn recentre(world: &[DVec3]) -> (DVec3, Vec<Vec3>) {
        let mut bounds = Aabb::EMPTY;
        world.iter().for_each(|&p| bounds.extend(p));
        let origin = if bounds.is_empty() { DVec3::ZERO } else { bounds.center() };
        (origin, world.iter().map(|&p| (p - origin).as_vec3()).collect())
    }
}

/// What a material's alpha (its `alpha` factor times the texture's alpha) does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is solid.
    Opaque,
    /// Alpha-tested: where alpha is below `cutoff` the surface is a hole for every pass
    /// (G-buffer, shadow maps, depth peel) and for the reference tracer's rays.
    Mask {
        /// The threshold, in [0, 1].
        cutoff: f32,
    },
    /// Blended (glTF `BLEND`, OBJ `d` < 1 without `map_d`): AO has no transparency, so vrao
    /// draws it alpha-tested at [`BLEND_CUTOFF`]: mostly opaque texels occlude and
    /// receive AO, mostly transparent ones (glass) are holes.
    Blend,
}

/// The alpha below which a [`AlphaMode::Blend`] texel is a hole.
pub const BLEND_CUTOFF: f32 = 0.5;

impl AlphaMode {
    /// The alpha below which a texel is a hole, or `None` for a solid material.
    pub fn cutoff(&self) -> Option<f32> {
        match *self {
            AlphaMode::Opaque => None,
            AlphaMode::Mask { cutoff } => Some(cutoff),
            AlphaMode::Blend => Some(BLEND_CUTOFF),
        }
    }
}

/// A diffuse material, as an MTL entry describes it.
#[derive(Clone, Debug)]
pub struct Material {
    /// Name from the source file (or the builtin's name).
    pub name: String,
    /// Linear diffuse reflectance (MTL `Kd`), each channel in [0, 1].
    pub diffuse: Vec3,
    /// Emitted radiance (MTL `Ke`), linear, unbounded.
    pub emissive: Vec3,
    /// Diffuse texture (MTL `map_Kd`), multiplied with `diffuse`; its alpha channel
    /// multiplies `alpha`.
    pub diffuse_texture: Option<Texture>,
    /// Emission texture (glTF `emissiveTexture`, sRGB), multiplied with `emissive`.
    pub emissive_texture: Option<Texture>,
    /// Tangent-space normal texture (glTF `normalTexture`, linear), with its `scale`
    /// (how far the texture tilts the normal: x and y scaled).
    pub normal_texture: Option<(Texture, f32)>,
    /// Baked ambient occlusion (glTF `occlusionTexture`, red channel, linear), with its
    /// `strength` (1 + strength × (texel − 1)); combined with the screen-space AO in the
    /// lighting by taking the smaller of the two (`composite.wgsl`).
    pub occlusion_texture: Option<(Texture, f32)>,
    /// Alpha factor (MTL `d`, glTF `baseColorFactor.a`), in [0, 1].
    pub alpha: f32,
    /// What alpha does (opaque, alpha-tested or blended).
    pub alpha_mode: AlphaMode,
    /// Whether both faces are drawn (OBJ and built-in materials; glTF `doubleSided`). A
    /// single-sided surface is culled from behind (counter-clockwise is its front) in
    /// every raster pass, shadow maps included, and by the reference tracer's rays.
    pub double_sided: bool,
}

impl Material {
    /// A material of one diffuse colour, neither emissive nor textured.
    pub fn plain(name: &str, diffuse: Vec3) -> Self {
        Material {
            name: name.into(),
            diffuse,
            emissive: Vec3::ZERO,
            diffuse_texture: None,
            emissive_texture: None,
            normal_texture: None,
            occlusion_texture: None,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            double_sided: true,
        }
    }

    /// The alpha below which this material is a hole, or `None` when it is solid
    /// everywhere (opaque, or an alpha test that nothing can fail).
    pub fn alpha_cutoff(&self) -> Option<f32> {
        self.alpha_cutoff_with_vertex_alpha(1.0)
    }

    /// [`Material::alpha_cutoff`] on meshes whose vertex colours' alpha (which multiplies
    /// the material's) goes down to `vertex_alpha_min`.
    pub fn alpha_cutoff_with_vertex_alpha(&self, vertex_alpha_min: f32) -> Option<f32> {
        let cutoff = self.alpha_mode.cutoff()?;
        let texture_alpha_min =
            self.diffuse_texture.as_ref().map_or(255, |t| t.rgba8.chunks_exact(4).map(|c| c[3]).min().unwrap_or(255));
        let lowest = self.alpha * vertex_alpha_min * texture_alpha_min as f32 / 255.0;
        (lowest < cutoff).then_some(cutoff)
    }
}

/// A light source of the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Light arriving along `direction` (unit, pointing from the light into the scene);
    /// `intensity` is the irradiance on a surface facing it.
    Directional {
        /// Unit direction of travel, from the light into the scene.
        direction: Vec3,
        /// Linear RGB colour.
        color: Vec3,
        /// Irradiance on a surface facing the light.
        intensity: f32,
    },
    /// An isotropic point light; `intensity` is radiant intensity (irradiance at 1 m).
    Point {
        /// World position in metres.
        position: DVec3,
        /// Linear RGB colour.
        color: Vec3,
        /// Radiant intensity (irradiance at 1 m).
        intensity: f32,
    },
    /// A spot light (glTF `KHR_lights_punctual` spot): a point light limited to a cone
    /// around `direction`, full inside `inner_cone`, fading smoothly to nothing at
    /// `outer_cone` (glTF's falloff: the square of a linear ramp in the cosine of the
    /// angle). Like point lights it casts no shadow map.
    Spot {
        /// World position in metres.
        position: DVec3,
        /// Unit direction the cone points along.
        direction: Vec3,
        /// Linear RGB colour.
        color: Vec3,
        /// Radiant intensity on the axis (irradiance at 1 m).
        intensity: f32,
        /// Half-angle (radians) inside which the light is at full intensity.
        inner_cone: f32,
        /// Half-angle (radians) beyond which there is no light; greater than `inner_cone`, at most π/2.
        outer_cone: f32,
    },
}

/// glTF's smooth spot cone falloff: 1 inside the inner cone, 0 outside the outer one,
/// between them the square of a linear ramp in the cosine of the angle off the axis
/// (`KHR_lights_punctual`'s recommended form). `cos_angle` is the cosine between the spot
/// direction and the direction from the light to the lit point.
pub fn spot_falloff(cos_angle: f32, inner_cone: f32, outer_cone: f32) -> f32 {
    let (cos_outer, scale) = spot_ramp(inner_cone, outer_cone);
    let ramp = ((cos_angle - cos_outer) * scale).clamp(0.0, 1.0);
    ramp * ramp
}

/// The cosine of the outer cone and the ramp's scale 1 / (cos inner − cos outer), kept
/// finite when the cones (nearly) coincide; the shaders take these two numbers.
pub fn spot_ramp(inner_cone: f32, outer_cone: f32) -> (f32, f32) {
    let (cos_inner, cos_outer) = (inner_cone.cos(), outer_cone.cos());
    (cos_outer, 1.0 / (cos_inner - cos_outer).max(1e-3))
}

impl Light {
    /// The sun used when a scene names no light: white, irradiance 3, arriving from above,
    /// in front (+Z) and to the left (−X) so that floors and front faces are both lit.
    pub fn default_sun() -> Light {
        Light::Directional { direction: Vec3::new(1.0, -2.0, -1.0).normalize(), color: Vec3::ONE, intensity: 3.0 }
    }
}

/// Axis-aligned bounds in world space (f64).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The smallest corner (+∞ for empty bounds).
    pub min: DVec3,
    /// The largest corner (−∞ for empty bounds).
    pub max: DVec3,
}

impl Aabb {
    /// Bounds of nothing: extending them by a point gives that point.
    pub const EMPTY: Aabb = Aabb { min: DVec3::splat(f64::INFINITY), max: DVec3::splat(f64::NEG_INFINITY) };
    /// Whether no point has been added.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
    /// Grows the bounds to contain `p`.
    pub fn extend(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// The bounds of both.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    /// The bounds of `points`; NaN on both sides when one of them has a NaN (an empty
    /// list gives [`Aabb::EMPTY`]).
    pub fn around(points: &[DVec3]) -> Aabb {
        if points.iter().any(|p| p.is_nan()) {
            return Aabb { min: DVec3::NAN, max: DVec3::NAN };
        }
        let mut b = Aabb::EMPTY;
        points.iter().for_each(|&p| b.extend(p));
        b
    }
    /// The eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, lo: f64, hi: f64| if i & bit == 0 { lo } else { hi };
            DVec3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            )
        })
    }
    /// The bounds of this box's corners moved by `m`: a box holding the moved box.
    pub fn transformed(&self, m: &DMat4) -> Aabb {
        Aabb::around(&self.corners().map(|c| m.transform_point3(c)))
    }
    /// The centre point.
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }
    /// Edge lengths along x, y and z.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// A head pose that frames these bounds for a ~90° field of view: in front (+Z),
    /// slightly above the centre and looking at it, far enough back that the bounding
    /// sphere fits (half diagonal / tan 40°) plus half the depth, so the eye is outside
    /// the box. An open-fronted model such as the Cornell box is seen from its open side.
    /// A model smaller than [`FRAMING_MIN_EXTENT`] is framed as if it were that size: the
    /// eyes sit 32 mm either side of the head, so closer than that a small model would
    /// leave both eyes' views (and fall inside the 5 cm near plane); from there it lies
    /// whole beyond the near plane in both eyes, as a jeweller's loupe would show it.
    /// Empty bounds give a standing head at the origin looking along −Z.
    pub fn framing_pose(&self) -> HeadPose {
        let size = self.size();
        let diagonal = size.length();
        if self.is_empty() || !diagonal.is_finite() {
            return HeadPose::look_at(DVec3::new(0.0, 1.6, 0.0), DVec3::new(0.0, 1.6, -1.0))
                .unwrap_or(HeadPose::IDENTITY);
        }
        let extent = diagonal.max(FRAMING_MIN_EXTENT);
        let distance = 0.5 * extent / 40f64.to_radians().tan() + 0.5 * size.z;
        let centre = self.center();
        let eye = centre + DVec3::new(0.0, 0.1 * extent, distance);
        HeadPose::look_at(eye, centre).unwrap_or(HeadPose { position: eye, orientation: glam::DQuat::IDENTITY })
    }
}

/// The smallest diagonal [`Aabb::framing_pose`] frames as it is, metres: twice a typical
/// IPD (64 mm), so each eye sees the model within ~25° of its centre, and its front lies
/// at least 7.6 cm away, beyond the default 5 cm near plane.
pub const FRAMING_MIN_EXTENT: f64 = 0.128;

/// The head pose over time: one key for a static head, several for a scripted path.
/// Between keys, position is interpolated linearly and orientation by slerp.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadPath {
    /// (time in seconds, pose), sorted by time, at least one key.
    pub keys: Vec<(f64, HeadPose)>,
}

impl HeadPath {
    /// A head that stays at one pose.
    pub fn fixed(pose: HeadPose) -> Self {
        HeadPath { keys: vec![(0.0, pose)] }
    }
    /// The pose at time `t` (seconds); clamps to the first and last key.
    pub fn pose_at(&self, t: f64) -> HeadPose {
        let keys = &self.keys;
        if t <= keys[0].0 || keys.len() == 1 {
            return keys[0].1;
        }
        for pair in keys.windows(2) {
            let ((t0, a), (t1, b)) = (pair[0], pair[1]);
            if t <= t1 {
                let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
                return HeadPose {
                    position: a.position.lerp(b.position, s),
                    orientation: a.orientation.slerp(b.orientation, s),
                };
            }
        }
        keys[keys.len() - 1].1
    }
}

/// Everything rendered: meshes, their materials, lights, an optional environment and
/// the head's path. Load one with [`Scene::load`] (`builtin:NAME`, a `.toml` scene file
/// or an `.obj`).
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name from the source file (or the builtin's name).
    pub name: String,
    /// The triangle meshes.
    pub meshes: Vec<Mesh>,
    /// Materials, indexed by [`Mesh::material`].
    pub materials: Vec<Material>,
    /// Directional and point lights (a default sun when the source names none).
    pub lights: Vec<Light>,
    /// Distant environment light (ambient and SSDO's incoming radiance), if any.
    pub environment: Option<Environment>,
    /// The head pose over time (one key for a still head).
    pub head: HeadPath,
    /// The motion hierarchy that moving meshes hang from ([`Mesh::node`]); empty for a
    /// still scene (`animation.rs`).
    pub nodes: Vec<Node>,
}

impl Scene {
    /// World-space bounds of every mesh, moving ones over their whole animation.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for m in self.meshes.iter().filter(|m| m.node.is_none()) {
            for p in &m.positions {
                b.extend(m.origin + p.as_dvec3());
            }
        }
        self.swept_corners().into_iter().for_each(|p| b.extend(p));
        b
    }

    /// Key times at which a moving object's bounds are sampled over the loop.
    const SWEEP_SAMPLES: usize = 64;

    /// World-space corners of every moving mesh's local bounding box, at
    /// 64 times over the animation loop (and at its end): what the
    /// bounds and the shadow maps' fits must contain. Empty for a still scene.
    pub fn swept_corners(&self) -> Vec<DVec3> {
        if !self.meshes.iter().any(|m| m.node.is_some()) {
            return Vec::new();
        }
        let period = self.animation_period();
        let times: Vec<DMat4Set> = (0..=Self::SWEEP_SAMPLES)
            .map(|k| animation::world_transforms(&self.nodes, period * k as f64 / Self::SWEEP_SAMPLES as f64))
            .collect();
        let mut corners = Vec::new();
        for m in &self.meshes {
            let Some(node) = m.node else { continue };
            let mut local = Aabb::EMPTY;
            m.positions.iter().filter(|p| p.is_finite()).for_each(|p| local.extend(m.origin + p.as_dvec3()));
            if local.is_empty() {
                continue;
            }
            for transforms in &times {
                let Some(world) = transforms.get(node) else { continue };
                for i in 0..8 {
                    let pick = |bit: usize, lo: f64, hi: f64| if i & bit == 0 { lo } else { hi };
                    let c = DVec3::new(
                        pick(1, local.min.x, local.max.x),
                        pick(2, local.min.y, local.max.y),
                        pick(4, local.min.z, local.max.z),
                    );
                    corners.push(world.transform_point3(c));
                }
            }
        }
        corners
    }

    /// Whether some mesh moves (hangs from an animated node).
    pub fn is_animated(&self) -> bool {
        self.meshes.iter().any(|m| m.node.is_some()) && self.animation_period() > 0.0
    }

    /// Whether some material is alpha-tested (or blended) and can actually fail the test.
    pub fn has_alpha_test(&self) -> bool {
        self.alpha_cutoffs().iter().any(Option::is_some)
    }

    /// Each material's alpha-test cutoff ([`Material::alpha_cutoff`]), the vertex colours'
    /// alpha of the meshes drawn with it included.
    pub fn alpha_cutoffs(&self) -> Vec<Option<f32>> {
        let mut vertex_alpha_min = vec![1.0f32; self.materials.len()];
        for mesh in &self.meshes {
            if let Some(lowest) = vertex_alpha_min.get_mut(mesh.material) {
                *lowest = mesh.colors.iter().map(|c| c.w).fold(*lowest, f32::min);
            }
        }
        self.materials.iter().zip(vertex_alpha_min).map(|(m, v)| m.alpha_cutoff_with_vertex_alpha(v)).collect()
    }

    /// The loop period of the animation: the last key time over every track (0 when
    /// nothing is animated).
    pub fn animation_period(&self) -> f64 {
        self.nodes.iter().map(|n| n.tracks.end()).fold(0.0, f64::max)
    }

    /// `t` wrapped into the animation's loop period (0 when nothing moves; non-finite `t`
    /// gives 0).
    pub fn animation_time(&self, t: f64) -> f64 {
        let period = self.animation_period();
        if period > 0.0 && t.is_finite() {
            t.rem_euclid(period)
        } else {
            0.0
        }
    }

    /// World-from-local transforms of every node at scene time `t` (wrapped into the loop).
    pub fn node_transforms(&self, t: f64) -> Vec<DMat4> {
        animation::world_transforms(&self.nodes, self.animation_time(t))
    }

    /// The scene frozen at time `t`: every moving mesh baked into world space, no nodes
    /// (what the reference tracer renders for a frame at that time).
    pub fn at_time(&self, t: f64) -> Scene {
        if self.nodes.is_empty() {
            return self.clone();
        }
        let transforms = self.node_transforms(t);
        let meshes = self
            .meshes
            .iter()
            .map(|m| match m.node.and_then(|n| transforms.get(n)) {
                Some(world) => bake(m, world),
                None => m.clone(),
            })
            .collect();
        Scene { meshes, nodes: Vec::new(), ..self.clone() }
    }

    /// A default occlusion radius for this scene: 8 % of its bounding-box diagonal,
    /// kept within 1 cm and 1 m (room-scale detail; a cathedral still gets 1 m); the
    /// figures are `settings::AO_RADIUS_*`.
    pub fn suggested_ao_radius(&self) -> f32 {
        use crate::settings::{AO_RADIUS_MAX, AO_RADIUS_MIN, AO_RADIUS_OF_DIAGONAL};
        let b = self.bounds();
        let diagonal = if b.is_empty() { 0.0 } else { b.size().length() };
        ((AO_RADIUS_OF_DIAGONAL * diagonal) as f32).clamp(AO_RADIUS_MIN, AO_RADIUS_MAX)
    }

    /// Triangles over all meshes.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len() / 3).sum()
    }

    /// True when some material emits light.
    pub fn has_emissive(&self) -> bool {
        self.materials.iter().any(|m| m.emissive.max_element() > 0.0)
    }

    /// Loads `builtin:NAME`, a `.toml` scene file, a bare `.obj`, or a `.gltf`/`.glb`.
    pub fn load(spec: &str) -> Result<Scene> {
        let (scene, file) = match spec.strip_prefix("builtin:") {
            Some(name) => (builtin::load(name)?, None),
            None => {
                let path = Path::new(spec);
                // Says what is there when it is not a regular file (a folder, a FIFO, a
                // device), and why a path `exists()` calls missing (a symlink loop) is unreadable.
                crate::files::check_regular_file(path)?;
                (Self::load_file(path)?, Some(path))
            }
        };
        // What each loader checked part by part, for the whole scene: motion that carries a
        // mesh beyond the far bound, a camera beyond it, the triangle and vertex budget.
        let trouble = limits::motion_trouble(&scene.meshes, &scene.nodes)
            .or_else(|| limits::head_trouble(&scene.head))
            .or_else(|| limits::GeometryBudget::of(&scene.meshes).trouble());
        match (trouble, file) {
            (None, _) => Ok(scene),
            (Some(trouble), Some(path)) => Err(Error::in_file(path, trouble)),
            (Some(trouble), None) => Err(Error::input(format!("{spec}: {trouble}"))),
        }
    }

    /// Loads a `.toml` scene file, a bare `.obj`, or a `.gltf`/`.glb` by its extension.
    fn load_file(path: &Path) -> Result<Scene> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) {
            Some(ext) if ext == "toml" => file::load(path),
            Some(ext) if ext == "obj" => obj::load_bare(path),
            #[cfg(feature = "gltf")]
            Some(ext) if ext == "gltf" || ext == "glb" => gltf::load(path),
            #[cfg(not(feature = "gltf"))]
            Some(ext) if ext == "gltf" || ext == "glb" => Err(gltf_not_built(path)),
            _ => Err(Error::in_file(
                path,
                "unknown scene type: expected builtin:NAME, a .toml scene file, an .obj, a .gltf or a .glb",
            )),
        }
    }
}

/// Every node's world transform at one time.
type DMat4Set = Vec<DMat4>;

/// `mesh` moved into world space by `world` (positions and normals; a mirroring transform
/// reverses the winding).
fn bake(mesh: &Mesh, world: &DMat4) -> Mesh {
    let points: Vec<DVec3> =
        mesh.positions.iter().map(|p| world.transform_point3(mesh.origin + p.as_dvec3())).collect();
    let (origin, positions) = Mesh::recentre(&points);
    let normal_matrix = glam::DMat3::from_mat4(*world).inverse().transpose();
    let normals = mesh.normals.iter().map(|n| (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3()).collect();
    let mut indices = mesh.indices.clone();
    if glam::DMat3::from_mat4(*world).determinant() < 0.0 {
        indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
    }
    Mesh {
        colors: mesh.colors.clone(),
        tangents: transform_tangents(&mesh.tangents, glam::DMat3::from_mat4(*world)),
        name: mesh.name.clone(),
        origin,
        positions,
        normals,
        uvs: mesh.uvs.clone(),
        uvs1: mesh.uvs1.clone(),
        indices,
        material: mesh.material,
        node: None,
    }
}

/// Tangents moved by the linear part of a transform: the direction along +u follows the
/// surface, and a mirroring transform flips the bitangent's sign.
pub fn transform_tangents(tangents: &[Vec4], linear: glam::DMat3) -> Vec<Vec4> {
    let flip = if linear.determinant() < 0.0 { -1.0 } else { 1.0 };
    tangents
        .iter()
        .map(|t| (linear * t.truncate().as_dvec3()).normalize_or_zero().as_vec3().extend(t.w * flip))
        .collect()
}

/// The refusal of a glTF by a vrao built without the `gltf` feature.
#[cfg(not(feature = "gltf"))]
pub(crate) fn gltf_not_built(path: &Path) -> Error {
    Error::in_file(path, "glTF needs vrao built with the `gltf` feature (on by default)")
}

/// The scene `vrao render` draws when none is named: the furnished room, whose table and
/// chairs on thin legs, blind, shelves and room corners show what AO adds (contact shadows,
/// crevices, corners) where the near-empty `room` shows almost nothing.
pub const RENDER_DEFAULT: &str = "builtin:furnished";

/// The public scenes' directory: `$VRAO_SCENES`, or `shared/scenes` beside the repository
/// this crate was built from (found from the crate's own place in it, so the dev profile and
/// an IDE that do not read `.cargo/config.toml` find it too), when it exists.
pub fn shared_scenes_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("VRAO_SCENES") {
        Some(dir) => PathBuf::from(dir),
        // crates/vrao-render -> the repository -> the folder beside it.
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes"),
    };
    dir.is_dir().then_some(dir)
}
