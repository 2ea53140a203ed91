//! How large a finite scene value may be before the renderer cannot draw it: light that
//! would overflow the half-float HDR buffer (every lit pixel then turns to infinity,
//! which the tone mapper shows as black), geometry so far away or so small that f32
//! positions, depths and shadow maps lose it (a frame of sky), and textures larger than
//! the device takes. The loaders refuse such values naming the file and line; these are
//! the bounds and their messages, in one place.

use super::{Mesh, Scene};
use crate::error::{Error, Result};

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
fn shortest(value: f64) -> String {
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
    fn a_texture_over_the_device_limit_is_refused_naming_its_file_and_the_limit() {
        let mut scene = crate::scene::builtin::load("plane").unwrap();
        let mut material = Material::plain("wide", Vec3::ONE);
        let texture = Texture {
            sampling: Default::default(),
            width: 17,
            height: 1,
            rgba8: vec![255; 17 * 4],
            source: Some(std::path::PathBuf::from("tex/wide.png")),
        };
        material.diffuse_texture = Some(texture);
        scene.materials.push(material);
        assert!(check_texture_sizes(&scene, 17, "gpu").is_ok());
        let e = check_texture_sizes(&scene, 16, "gpu").unwrap_err().to_string();
        assert!(e.starts_with("tex/wide.png: ") && e.contains("17x1") && e.contains("at most 16"), "{e}");
    }
}
