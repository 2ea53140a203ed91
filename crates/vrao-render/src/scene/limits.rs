//! How large a finite scene value may be before the renderer cannot draw it: light that
//! would overflow the half-float HDR buffer (every lit pixel then turns to infinity,
//! which the tone mapper shows as black), geometry so far away or so small that f32
//! positions, depths and shadow maps lose it (a frame of sky), and textures larger than
//! the device takes. The loaders refuse such values naming the file and line; these are
//! the bounds and their messages, in one place.

use super::{Mesh, Scene};
use vrao_ao::{Error, Result};

/// The brightest radiance a light, emitter or sky multiplier may give (linear, per colour
/// channel): the largest finite half float, the HDR buffer's format. One light at this
/// level already saturates every surface it faces.
pub const RADIANCE_MAX: f64 = super::environment::MAX_RADIANCE as f64;

/// The farthest a vertex may lie from the world origin, in metres (1000 km): vrao's
/// scenes are rooms and buildings; beyond this f32 depth and shadow-map texels are larger
/// than whole objects and the geometry vanishes.
pub const COORDINATE_MAX_M: f64 = 1.0e6;

/// The smallest mesh scale: a smaller one makes f32 offsets (and so whole meshes)
/// collapse to a point.
pub const SCALE_MIN: f64 = 1.0e-6;

/// The largest scale an animation key may give: a metre-sized mesh at this scale already
/// reaches [`COORDINATE_MAX_M`].
pub const SCALE_MAX: f64 = 1.0e6;

/// The most triangles a scene may hold, over every mesh instance of every file it places
/// (20 million): the budget of a scene file, a glTF, an OBJ and a built-in scene alike.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// The most vertices a scene may hold, over every mesh instance (20 million).
pub const MAX_VERTICES: usize = 20_000_000;
/// The most meshes a scene draws (each one draw in every raster pass, per eye pass): a
/// city block's worth; a million one-triangle primitives spent minutes and gigabytes on
/// draw records before this bound.
pub const MAX_MESHES: usize = 65_536;
/// The most bytes of decoded texels (RGBA8, before mipmaps) a scene's distinct images
/// may hold together: one image at the largest side, or many smaller ones.
pub const MAX_TEXTURE_BYTES: u64 = 1 << 30;

/// The largest texture side in texels, for every image a scene names.
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

/// Why a value or a file's content (or a runtime's answer, such as a headset's mask) is
/// refused, in one line, before the caller says where it came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Trouble(pub String);

impl std::fmt::Display for Trouble {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<String> for Trouble {
    fn from(message: String) -> Trouble {
        Trouble(message)
    }
}

impl From<&str> for Trouble {
    fn from(message: &str) -> Trouble {
        Trouble(message.to_string())
    }
}

impl From<Trouble> for String {
    fn from(trouble: Trouble) -> String {
        trouble.0
    }
}

/// The triangles and vertices a scene holds so far, checked against [`MAX_TRIANGLES`] and
/// [`MAX_VERTICES`] as each part is added (so that a file placed many times is refused
/// before the memory for all of them is spent).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GeometryBudget {
    /// Triangles so far.
    pub triangles: usize,
    /// Vertices so far.
    pub vertices: usize,
    /// Meshes so far: each is a draw of every raster pass (a glTF primitive instance).
    pub meshes: usize,
}

impl GeometryBudget {
    /// The triangles and vertices of `meshes`.
    pub fn of(meshes: &[Mesh]) -> GeometryBudget {
        meshes.iter().fold(GeometryBudget::default(), |b, m| GeometryBudget {
            triangles: b.triangles + m.indices.len() / 3,
            vertices: b.vertices + m.positions.len(),
            meshes: b.meshes + 1,
        })
    }

    /// This budget with `more` added, or one-line trouble (naming what `what` adds) when
    /// the sum passes either limit.
    pub fn plus(self, more: GeometryBudget, what: &str) -> std::result::Result<GeometryBudget, Trouble> {
        let sum = GeometryBudget {
            triangles: self.triangles.saturating_add(more.triangles),
            vertices: self.vertices.saturating_add(more.vertices),
            meshes: self.meshes.saturating_add(more.meshes),
        };
        match sum.trouble() {
            Some(trouble) => Err(format!("{what} brings the scene to {trouble}").into()),
            None => Ok(sum),
        }
    }

    /// One-line trouble when these counts pass either limit.
    pub fn trouble(self) -> Option<String> {
        if self.meshes > MAX_MESHES {
            return Some(format!(
                "{} meshes (glTF primitives drawn, each instance one draw per pass), more than vrao's limit of \
                 {MAX_MESHES}: merge primitives that share a material",
                self.meshes
            ));
        }
        (self.triangles > MAX_TRIANGLES || self.vertices > MAX_VERTICES).then(|| {
            format!(
                "{} triangles and {} vertices, more than vrao's limit of {MAX_TRIANGLES} triangles and {MAX_VERTICES} \
                 vertices over the whole scene",
                self.triangles, self.vertices
            )
        })
    }
}

/// One-line trouble when a scene's distinct images hold more than [`MAX_TEXTURE_BYTES`]
/// of decoded texels (`what` brought them to `bytes`).
pub fn texture_budget_trouble(what: &str, bytes: u64) -> Option<String> {
    (bytes > MAX_TEXTURE_BYTES).then(|| {
        format!(
            "{what} brings the scene's textures to {} MiB of texels, over vrao's budget of {} MiB",
            bytes >> 20,
            MAX_TEXTURE_BYTES >> 20
        )
    })
}

/// `what` (a colour times its intensity, per channel) as one-line trouble when some
/// channel is brighter than [`RADIANCE_MAX`].
pub fn radiance_trouble(what: &str, brightest: f64) -> Option<String> {
    (brightest > RADIANCE_MAX).then(|| {
        format!(
            "{what} {} is brighter than {RADIANCE_MAX} (the HDR buffer's largest value, where every lit pixel \
             already saturates)",
            shortest(brightest)
        )
    })
}

/// One-line trouble when the coordinate `value` (m) lies beyond [`COORDINATE_MAX_M`].
pub fn coordinate_trouble(what: &str, value: f64) -> Option<String> {
    (value.abs() > COORDINATE_MAX_M)
        .then(|| format!("{what} {} m is farther than {COORDINATE_MAX_M:e} m from the origin", shortest(value)))
}

/// `value` in exponent form, as short as its precision allows: a value read as f32
/// prints as the file wrote it (3e38, not 3.0000000054977558e38).
pub(crate) fn shortest(value: f64) -> String {
    let single = value as f32;
    if single.is_finite() && (single as f64 - value).abs() <= value.abs() * 1e-7 {
        format!("{single:e}")
    } else {
        format!("{value:e}")
    }
}

/// One-line trouble when a mesh scale factor is smaller than [`SCALE_MIN`] in size.
pub fn scale_trouble(scale: f64) -> Option<String> {
    (scale.abs() < SCALE_MIN)
        .then(|| format!("scale {} is smaller than {SCALE_MIN:e} (the mesh would vanish)", shortest(scale)))
}

/// One-line trouble for an animation key's scale factor: larger than [`SCALE_MAX`] in
/// size, or smaller than [`SCALE_MIN`] but not 0 (a key of exactly 0 hides the object
/// while it holds, as content does; the renderer draws nothing of it then).
pub fn key_scale_trouble(what: &str, scale: f64) -> Option<String> {
    if scale.abs() > SCALE_MAX {
        return Some(format!("{what} {} is larger than {SCALE_MAX:e}", shortest(scale)));
    }
    (scale != 0.0 && scale.abs() < SCALE_MIN).then(|| {
        format!("{what} {} is smaller than {SCALE_MIN:e} and not 0 (the mesh would collapse)", shortest(scale))
    })
}

/// One-line trouble when a texture is wider or taller than [`MAX_TEXTURE_SIDE`] (or empty),
/// worded as the device's own check ([`check_texture_sizes`]) words it.
pub fn texture_side_trouble(width: u32, height: u32) -> Option<String> {
    if width == 0 || height == 0 {
        return Some(format!("{width}x{height} texels: an empty image"));
    }
    (width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE)
        .then(|| format!("{width}x{height} texels; vrao takes at most {MAX_TEXTURE_SIDE} per side (scale it down)"))
}

/// The image decoder's limits for textures: sides up to [`MAX_TEXTURE_SIDE`], and memory
/// for such a texture at 16 bits per channel (the image crate's own default, 512 MiB,
/// would refuse a valid 16384 × 16384 RGBA8 texture, 1 GiB).
pub fn texture_decoder_limits() -> image::Limits {
    let side = MAX_TEXTURE_SIDE as u64;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(side * side * 8);
    limits
}

/// Decodes an image file's bytes (PNG, JPEG, TGA, BMP, by content) under
/// [`texture_decoder_limits`]: a side over [`MAX_TEXTURE_SIDE`] is refused from the header,
/// before any texel is decoded.
pub fn decode_texture(bytes: &[u8]) -> std::result::Result<image::DynamicImage, Trouble> {
    let reader = || image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format();
    let (width, height) = reader().map_err(|e| e.to_string())?.into_dimensions().map_err(|e| e.to_string())?;
    if let Some(trouble) = texture_side_trouble(width, height) {
        return Err(trouble.into());
    }
    let mut reader = reader().map_err(|e| e.to_string())?;
    reader.limits(texture_decoder_limits());
    reader.decode().map_err(|e| e.to_string().into())
}

/// One-line trouble when some vertex of `mesh` (static, in world space) lies beyond
/// [`COORDINATE_MAX_M`]: the first such vertex, by its number in the mesh.
pub fn mesh_trouble(mesh: &Mesh) -> Option<String> {
    mesh.positions.iter().enumerate().find_map(|(i, p)| {
        let world = mesh.origin + p.as_dvec3();
        let farthest = world.abs().max_element();
        let trouble = coordinate_trouble(&format!("vertex {} of mesh '{}' lies at", i + 1, mesh.name), farthest);
        trouble.or_else(|| (!world.is_finite()).then(|| format!("mesh '{}' has a vertex at infinity", mesh.name)))
    })
}

/// One-line trouble when a moving mesh (one that hangs from a node of `nodes`) can reach
/// beyond [`COORDINATE_MAX_M`] over its animation: its local bounds carried up its chain
/// of nodes through every value their tracks take ([`super::animation::reach_in_world`]:
/// bounded from the keys, a cubic spline's overshoot between keys included, never
/// sampled), each key's value already in range but their product (a far key times a large
/// scale, a large placement of a moving root, a spline's tangents) not. The bound is
/// conservative: an animated rotation counts as any rotation.
pub fn motion_trouble(meshes: &[Mesh], nodes: &[super::Node]) -> Option<String> {
    for mesh in meshes {
        let Some(node) = mesh.node else { continue };
        let mut local = super::Aabb::EMPTY;
        mesh.positions.iter().filter(|p| p.is_finite()).for_each(|p| local.extend(mesh.origin + p.as_dvec3()));
        if local.is_empty() {
            continue;
        }
        let world = super::animation::reach_in_world(nodes, node, &local);
        let farthest = world.min.abs().max(world.max.abs()).max_element();
        if world.min.is_nan() || world.max.is_nan() || farthest.is_nan() || farthest > COORDINATE_MAX_M {
            let reach = if farthest.is_nan() || world.min.is_nan() { "NaN".to_string() } else { shortest(farthest) };
            return Some(format!(
                "moving mesh '{}' can reach {reach} m from the origin over its animation (bounded from its keys and \
                 their spline tangents), farther than {COORDINATE_MAX_M:e} m",
                mesh.name
            ));
        }
    }
    None
}

/// One-line trouble when a head pose of `head` (a scene file's head or path, a glTF's
/// camera) lies beyond [`COORDINATE_MAX_M`].
pub fn head_trouble(head: &super::HeadPath) -> Option<String> {
    head.keys.iter().find_map(|(t, pose)| {
        let what = match head.keys.len() {
            1 => "the head (camera) position".to_string(),
            _ => format!("the head (camera) position at t = {t} s"),
        };
        coordinate_trouble(&what, pose.position.abs().max_element())
    })
}

/// Refuses a scene with a texture wider or taller than `max_side` texels (the device's
/// `max_texture_dimension_2d`), naming the texture's file and the limit.
pub fn check_texture_sizes(scene: &Scene, max_side: u32, adapter: &str) -> Result<()> {
    for material in &scene.materials {
        let Some(texture) = &material.diffuse_texture else { continue };
        if texture.width.max(texture.height) > max_side {
            let message = format!(
                "texture of material '{}' is {}x{} texels; {adapter} takes at most {max_side} per side (scale it down)",
                material.name, texture.width, texture.height
            );
            return Err(match &texture.source {
                Some(file) => Error::in_file(file, message),
                None => Error::input(message),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Texture};
    use glam::{DVec3, Vec3};

    #[test]
    fn bounds_let_ordinary_values_through_and_name_the_rest() {
        assert_eq!(radiance_trouble("light color × intensity", 3.0), None);
        let bright = radiance_trouble("light color × intensity", 1e60).unwrap();
        assert!(bright.contains("1e60") && bright.contains("65504"), "{bright}");
        assert_eq!(coordinate_trouble("translate", -5000.0), None);
        assert!(coordinate_trouble("translate", 1e300).unwrap().contains("1e300 m"));
        assert_eq!(scale_trouble(0.01), None);
        assert!(scale_trouble(1e-300).unwrap().contains("1e-300"));
        let mut mesh = crate::scene::builtin::load("box").unwrap().meshes.remove(0);
        assert_eq!(mesh_trouble(&mesh), None);
        mesh.origin = DVec3::new(3e38, 0.0, 0.0);
        assert!(mesh_trouble(&mesh).unwrap().contains("vertex 1 of mesh"), "{:?}", mesh_trouble(&mesh));
    }

    #[test]
    fn the_texture_budget_takes_one_largest_image_and_refuses_more() {
        let largest = u64::from(MAX_TEXTURE_SIDE) * u64::from(MAX_TEXTURE_SIDE) * 4;
        assert_eq!(texture_budget_trouble("image 0", largest.min(MAX_TEXTURE_BYTES)), None);
        let e = texture_budget_trouble("image 3", MAX_TEXTURE_BYTES + 4).unwrap();
        assert_eq!(e, "image 3 brings the scene's textures to 1024 MiB of texels, over vrao's budget of 1024 MiB");
    }

    #[test]
    fn one_budget_for_the_scene_and_every_builtin_within_it() {
        let most = GeometryBudget { triangles: MAX_TRIANGLES, vertices: MAX_VERTICES, meshes: MAX_MESHES };
        assert_eq!(most.trouble(), None);
        let e = most.plus(GeometryBudget { triangles: 0, vertices: 0, meshes: 1 }, "mesh 'a'").unwrap_err().0;
        assert!(e.starts_with("mesh 'a' brings the scene to 65537 meshes") && e.contains("merge primitives"), "{e}");
        let most = GeometryBudget { meshes: 0, ..most };
        let e = most.plus(GeometryBudget { triangles: 1, vertices: 0, meshes: 0 }, "mesh obj 'a.obj'").unwrap_err().0;
        assert_eq!(
            e,
            "mesh obj 'a.obj' brings the scene to 20000001 triangles and 20000000 vertices, more than vrao's limit \
             of 20000000 triangles and 20000000 vertices over the whole scene"
        );
        for name in crate::scene::builtin::NAMES {
            let scene = crate::scene::Scene::load(&format!("builtin:{name}")).unwrap();
            assert_eq!(GeometryBudget::of(&scene.meshes).trouble(), None, "{name}");
            assert_eq!(motion_trouble(&scene.meshes, &scene.nodes), None, "{name}");
        }
        assert!(key_scale_trouble("s", 0.0).is_none() && key_scale_trouble("s", 1e6).is_none());
        assert!(key_scale_trouble("s", -1e-7).unwrap().contains("not 0"));
        assert!(key_scale_trouble("s", 2e6).unwrap().contains("larger than 1e6"));
    }

    #[test]
    fn a_splines_overshoot_between_keys_is_within_the_motion_bound() {
        use crate::scene::{Interpolation, Node, NodeTracks, Track, Trs};
        // Keys at 0, 10 and 640 s, every value 0: 65 samples over the loop fall every
        // 10 s, on the keys, and saw nothing; the first segment's tangents (±9e5 m/s, each
        // in range) carry the mesh 2.25e6 m out at t = 5 s.
        let node = |b0: f64| Node {
            name: "thrown".into(),
            parent: None,
            base: glam::DMat4::IDENTITY,
            rest: Trs::IDENTITY,
            tracks: NodeTracks {
                translation: Some(Track {
                    interpolation: Interpolation::CubicSpline,
                    times: vec![0.0, 10.0, 640.0],
                    values: [0.0, 0.0, b0, -b0, 0.0, 0.0, 0.0, 0.0, 0.0].map(|x| DVec3::new(x, 0.0, 0.0)).to_vec(),
                }),
                ..Default::default()
            },
        };
        let mut mesh = crate::scene::builtin::load("box").unwrap().meshes.remove(0);
        mesh.node = Some(0);
        let thrown = node(9e5);
        let peak = thrown.tracks.translation.as_ref().unwrap().sample(5.0).x;
        assert!((peak - 2.25e6).abs() < 1.0, "{peak}");
        let e = motion_trouble(std::slice::from_ref(&mesh), &[thrown]).unwrap();
        assert!(e.starts_with(&format!("moving mesh '{}' can reach 3", mesh.name)), "{e}");
        assert!(e.ends_with("farther than 1e6 m"), "{e}");
        // A tenth of the tangent: 2.25e5 m at most, within.
        assert_eq!(motion_trouble(std::slice::from_ref(&mesh), &[node(9e4)]), None);
    }

    #[test]
    fn a_texture_over_the_device_limit_is_refused_naming_its_file_and_the_limit() {
        let mut scene = crate::scene::builtin::load("plane").unwrap();
        let mut material = Material::plain("wide", Vec3::ONE);
        let texture = Texture {
            sampling: Default::default(),
            width: 17,
            height: 1,
            rgba8: vec![255; 17 * 4].into(),
            source: Some(std::path::PathBuf::from("tex/wide.png")),
        };
        material.diffuse_texture = Some(texture);
        scene.materials.push(material);
        assert!(check_texture_sizes(&scene, 17, "gpu").is_ok());
        let e = check_texture_sizes(&scene, 16, "gpu").unwrap_err().to_string();
        assert!(e.starts_with("tex/wide.png: ") && e.contains("17x1") && e.contains("at most 16"), "{e}");
    }
}
