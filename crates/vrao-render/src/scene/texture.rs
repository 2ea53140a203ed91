//! Textures as materials use them: the decoded image and how it is sampled (wrap per
//! axis, filters, mipmaps, and `KHR_texture_transform`'s placement), read by the G-buffer
//! and the reference tracer alike.

use glam::{Affine2, Vec2};
use std::path::PathBuf;

/// An RGBA8 texture in sRGB encoding, row-major from the top-left texel.
#[derive(Clone, Debug)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width × height` texels, four bytes each; shared by every material slot that
    /// names the same image (decoded, held and uploaded once).
    pub rgba8: std::sync::Arc<Vec<u8>>,
    /// The image file it was decoded from (`None` when it came from no file of its own),
    /// named when the device cannot take the texture.
    pub source: Option<PathBuf>,
    /// How it is sampled.
    pub sampling: Sampling,
}

/// What happens to a texture coordinate outside [0, 1] on one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The texture tiles (glTF's default, and OBJ's).
    Repeat,
    /// The texture tiles, mirrored every other repeat.
    MirroredRepeat,
    /// The edge texel extends.
    ClampToEdge,
}

impl Wrap {
    /// Texel index `i` of a row of `n` brought into 0..n as this mode addresses it.
    pub fn texel(self, i: i64, n: i64) -> i64 {
        match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
            Wrap::ClampToEdge => i.clamp(0, n - 1),
        }
    }
}

/// Texel filtering.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The nearest texel.
    Nearest,
    /// Bilinear between the four nearest texels.
    Linear,
}

/// How a material samples one texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Wrap along u (glTF `wrapS`).
    pub wrap_u: Wrap,
    /// Wrap along v (glTF `wrapT`).
    pub wrap_v: Wrap,
    /// Filter when a texel covers more than a pixel (glTF `magFilter`).
    pub magnify: Filter,
    /// Filter within a mip level when a texel covers less than a pixel (glTF `minFilter`).
    pub minify: Filter,
    /// Filter between mip levels; `None` samples the full-size level only (glTF's
    /// `NEAREST`/`LINEAR` minification filters).
    pub mipmaps: Option<Filter>,
    /// From the mesh's texture coordinates to where the texture is read
    /// (`KHR_texture_transform`: translation · rotation · scale).
    pub transform: Affine2,
    /// The mesh's texture coordinate set it reads: 0 ([`super::Mesh::uvs`]) or 1
    /// ([`super::Mesh::uvs1`]); glTF `texCoord`, or `KHR_texture_transform`'s.
    pub tex_coord: u32,
}

impl Default for Sampling {
    /// glTF's default sampler (repeat on both axes) with the filters engines pick when
    /// the file names none: trilinear.
    fn default() -> Self {
        Sampling {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            magnify: Filter::Linear,
            minify: Filter::Linear,
            mipmaps: Some(Filter::Linear),
            transform: Affine2::IDENTITY,
            tex_coord: 0,
        }
    }
}

impl Sampling {
    /// The coordinates it reads of a point whose sets 0 and 1 are `uvs`.
    pub fn pick(&self, uvs: [Vec2; 2]) -> Vec2 {
        if self.tex_coord == 1 {
            uvs[1]
        } else {
            uvs[0]
        }
    }

    /// `uv` as the mesh gives it, moved by [`Sampling::transform`].
    pub fn place(&self, uv: Vec2) -> Vec2 {
        self.transform.transform_point2(uv)
    }
}

/// An sRGB-encoded byte as a linear value in [0, 1].
pub fn srgb_to_linear(byte: u8) -> f32 {
    let c = f64::from(byte) / 255.0;
    (if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }) as f32
}

/// `KHR_texture_transform`'s matrix: offset · rotation · scale, the rotation as the
/// Khronos sample viewer applies it (u' = cos·u + sin·v, v' = −sin·u + cos·v: the UVs
/// turn counter-clockwise as the texture is drawn, v pointing down).
pub fn uv_transform(offset: Vec2, rotation: f32, scale: Vec2) -> Affine2 {
    let (sin, cos) = rotation.sin_cos();
    let rotate = glam::Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos));
    Affine2::from_mat2_translation(rotate * glam::Mat2::from_diagonal(scale), offset)
}

/// The offset, rotation and scale that [`uv_transform`] makes `transform` from (a
/// transform with shear has none; this gives the nearest).
pub fn uv_transform_parts(transform: &Affine2) -> (Vec2, f32, Vec2) {
    let (u, v) = (transform.matrix2.x_axis, transform.matrix2.y_axis);
    let rotation = (-u.y).atan2(u.x);
    let flip = if transform.matrix2.determinant() < 0.0 { -1.0 } else { 1.0 };
    (transform.translation, rotation, Vec2::new(u.length(), flip * v.length()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes_address_texels_as_the_gpu_does() {
        assert_eq!(Wrap::Repeat.texel(-1, 4), 3);
        assert_eq!(Wrap::Repeat.texel(9, 4), 1);
        assert_eq!(Wrap::MirroredRepeat.texel(4, 4), 3);
        assert_eq!(Wrap::MirroredRepeat.texel(-1, 4), 0);
        assert_eq!(Wrap::MirroredRepeat.texel(8, 4), 0);
        assert_eq!(Wrap::ClampToEdge.texel(9, 4), 3);
        assert_eq!(Wrap::ClampToEdge.texel(-2, 4), 0);
    }

    #[test]
    fn uv_transform_turns_uvs_as_the_sample_viewer_and_splits_back_into_its_parts() {
        let quarter = uv_transform(Vec2::ZERO, std::f32::consts::FRAC_PI_2, Vec2::ONE);
        // u' = cos·u + sin·v, v' = −sin·u + cos·v.
        assert!(quarter.transform_point2(Vec2::X).abs_diff_eq(Vec2::new(0.0, -1.0), 1e-6));
        assert!(quarter.transform_point2(Vec2::Y).abs_diff_eq(Vec2::new(1.0, 0.0), 1e-6));
        let (offset, rotation, scale) = (Vec2::new(0.5, -0.25), 0.3f32, Vec2::new(1.5, 2.0));
        let t = uv_transform(offset, rotation, scale);
        // Scale first, then rotate, then offset.
        let expected = offset + Vec2::new(0.3f32.cos() * 1.5, -0.3f32.sin() * 1.5);
        assert!(t.transform_point2(Vec2::X).abs_diff_eq(expected, 1e-6));
        let (o, r, s) = uv_transform_parts(&t);
        assert!(o.abs_diff_eq(offset, 1e-6) && (r - rotation).abs() < 1e-6 && s.abs_diff_eq(scale, 1e-5));
    }
}
