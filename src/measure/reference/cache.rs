//! A disk cache for reference images.
//!
//! A file is named by a 64-bit FNV-1a hash of everything that determines the result:
//! the scene's content (vertex positions, normals, uvs, colours, tangents and indices with
//! their mesh origins, materials with their textures' texels and sampling, lights, the environment's texels and intensity), the eyes'
//! poses and fields of view, the image size, the settings, [`super::TRACER_VERSION`] and
//! [`FORMAT_VERSION`]. Names (of the scene, meshes, materials) and the head path do not
//! change the result and are left out. Floats are hashed by their bits.
//!
//! The file format, all little-endian:
//!
//! ```text
//! magic "VRAOREF\0" | format version u32 | key u64
//! width u32 | height u32 | stride u32 | layers u32 | grid width u32 | grid height u32
//! rays u64 | seconds f64 | build seconds f64 | rays per second f64 | noise f64 | hit pixels u64
//! per layer, per cell (row-major): hit u8, depth, ao, ao_falloff, ao_std_error f32,
//!                                  environment_visible, bounce, unoccluded 3 × f32 each,
//!                                  ambient_std_error, bounce_std_error 4 × f32 each
//! FNV-1a 64 of every byte above, u64
//! ```
//!
//! A file that is truncated, corrupt, of another version or for another key is ignored
//! with a warning and traced again (and overwritten).

use super::{grid_size, Progress, ReferenceImage, ReferencePixel, ReferenceSettings, ReferenceStats};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use vrao_ao::Eye;
use vrao_render::scene::{Filter, Light, Scene, Texture, Wrap};

/// Version of the cache file layout.
pub const FORMAT_VERSION: u32 = 2;

const MAGIC: &[u8; 8] = b"VRAOREF\0";
const PIXEL_BYTES: usize = 1 + 21 * 4;
const HEADER_BYTES: usize = 8 + 4 + 8 + 6 * 4 + 8 + 4 * 8 + 8;

/// FNV-1a, 64 bit: stable across runs, platforms and Rust versions (unlike std's hasher).
#[derive(Clone, Copy, Debug)]
pub(super) struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub(super) fn bytes(&mut self, bytes: &[u8]) {
        let mut h = self.0;
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.0 = h;
    }
    pub(super) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(super) fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        for x in v {
            self.u32(x.to_bits());
        }
    }
    pub(super) fn f64s(&mut self, v: &[f64]) {
        for x in v {
            self.u64(x.to_bits());
        }
    }
    pub(super) fn finish(&self) -> u64 {
        self.0
    }
}

/// The cache key of a trace (see the module docs for what it covers).
pub fn cache_key(scene: &Scene, eyes: &[Eye], size: (u32, u32), settings: &ReferenceSettings) -> u64 {
    let mut h = Fnv64::default();
    h.bytes(MAGIC);
    h.u32(FORMAT_VERSION);
    h.u32(super::TRACER_VERSION);
    hash_meshes(&mut h, scene);
    hash_materials(&mut h, scene);
    hash_lights(&mut h, scene);
    hash_environment(&mut h, scene);
    hash_eyes(&mut h, eyes);
    h.u32(size.0);
    h.u32(size.1);
    h.f64s(&[settings.radius, settings.near]);
    h.u32(settings.rays_per_pixel);
    h.u32(settings.stride);
    h.finish()
}

/// Hashes the meshes' count and each one's origin, vertices, indices and material index.
fn hash_meshes(h: &mut Fnv64, scene: &Scene) {
    h.u64(scene.meshes.len() as u64);
    for m in &scene.meshes {
        h.f64s(&m.origin.to_array());
        h.f32s(bytemuck::cast_slice(&m.positions));
        h.f32s(bytemuck::cast_slice(&m.normals));
        h.f32s(bytemuck::cast_slice(&m.uvs));
        h.f32s(bytemuck::cast_slice(&m.colors));
        h.f32s(bytemuck::cast_slice(&m.tangents));
        h.u64(m.indices.len() as u64);
        h.bytes(bytemuck::cast_slice(&m.indices));
        h.u64(m.material as u64);
    }
}

/// Hashes the materials' count and each one's colours, the textures the tracer reads
/// (base colour, emission, normal with its scale), alpha and alpha mode. The occlusion
/// texture is not part of the reference and is left out.
fn hash_materials(h: &mut Fnv64, scene: &Scene) {
    h.u64(scene.materials.len() as u64);
    for m in &scene.materials {
        h.f32s(&m.diffuse.to_array());
        h.f32s(&m.emissive.to_array());
        hash_texture(h, m.diffuse_texture.as_ref());
        hash_texture(h, m.emissive_texture.as_ref());
        hash_texture(h, m.normal_texture.as_ref().map(|(t, _)| t));
        h.f32s(&[m.normal_texture.as_ref().map_or(0.0, |&(_, scale)| scale)]);
        // Whether a material is alpha-tested may depend on its meshes' vertex colours,
        // which are hashed with the meshes: its alpha and mode are hashed whatever they are.
        h.f32s(&[m.alpha, m.alpha_mode.cutoff().unwrap_or(-1.0)]);
    }
}

/// Hashes whether there is a texture and, if so, its size, texels and what of its
/// sampling the tracer reads (transform, wrap per axis, magnification filter; it never
/// minifies).
fn hash_texture(h: &mut Fnv64, texture: Option<&Texture>) {
    let Some(t) = texture else { return h.u32(0) };
    h.u32(1);
    h.u32(t.width);
    h.u32(t.height);
    h.u64(t.rgba8.len() as u64);
    h.bytes(&t.rgba8);
    let s = &t.sampling;
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    };
    let filter = |f: Filter| match f {
        Filter::Nearest => 0,
        Filter::Linear => 1,
    };
    h.u32(wrap(s.wrap_u) | wrap(s.wrap_v) << 2 | filter(s.magnify) << 4);
    h.f32s(&s.transform.to_cols_array());
}

/// Hashes the lights' count and each one's kind and parameters.
fn hash_lights(h: &mut Fnv64, scene: &Scene) {
    h.u64(scene.lights.len() as u64);
    for light in &scene.lights {
        match *light {
            Light::Directional { direction, color, intensity } => {
                h.u32(0);
                h.f32s(&direction.to_array());
                h.f32s(&color.to_array());
                h.f32s(&[intensity]);
            }
            Light::Point { position, color, intensity } => {
                h.u32(1);
                h.f64s(&position.to_array());
                h.f32s(&color.to_array());
                h.f32s(&[intensity]);
            }
            Light::Spot { position, direction, color, intensity, inner_cone, outer_cone } => {
                h.u32(2);
                h.f64s(&position.to_array());
                h.f32s(&direction.to_array());
                h.f32s(&color.to_array());
                h.f32s(&[intensity, inner_cone, outer_cone]);
            }
        }
    }
}

/// Hashes whether there is an environment and, if so, its size, intensity and texels.
fn hash_environment(h: &mut Fnv64, scene: &Scene) {
    match &scene.environment {
        Some(env) => {
            h.u32(1);
            h.u32(env.width);
            h.u32(env.height);
            h.f32s(&[env.intensity]);
            h.f32s(bytemuck::cast_slice(&env.texels));
        }
        None => h.u32(0),
    }
}

/// Hashes the eyes' count and each one's pose and field of view.
fn hash_eyes(h: &mut Fnv64, eyes: &[Eye]) {
    h.u64(eyes.len() as u64);
    for eye in eyes {
        h.f64s(&eye.pose.position.to_array());
        h.f64s(&eye.pose.orientation.to_array());
        h.f32s(&[eye.fov.left, eye.fov.right, eye.fov.up, eye.fov.down]);
    }
}

/// The file in `cache_dir` that holds the result for `key`.
pub fn cache_file(cache_dir: &Path, key: u64) -> PathBuf {
    cache_dir.join(format!("reference-{key:016x}.bin"))
}

/// As [`super::trace`], but reads the result from `cache_dir` when an intact file for the same
/// inputs is there, and otherwise traces and writes one (creating the directory).
/// A cache file that cannot be read is traced again with a warning; one that cannot be
/// written is an [`Error::Output`] naming it.
pub fn trace_cached(
    cache_dir: &Path,
    scene: &Scene,
    eyes: &[Eye],
    size: (u32, u32),
    settings: &ReferenceSettings,
    progress: &mut dyn FnMut(Progress),
) -> Result<ReferenceImage> {
    trace_cached_visible(cache_dir, scene, eyes, size, settings, None, progress)
}

/// [`trace_cached`] of only the pixels the lens shows ([`super::trace_visible`]); the
/// coverage is part of the key.
pub fn trace_cached_visible(
    cache_dir: &Path,
    scene: &Scene,
    eyes: &[Eye],
    size: (u32, u32),
    settings: &ReferenceSettings,
    coverage: Option<&[Option<Vec<u8>>]>,
    progress: &mut dyn FnMut(Progress),
) -> Result<ReferenceImage> {
    settings.validate()?;
    let mut key = cache_key(scene, eyes, size, settings);
    if let Some(coverage) = coverage {
        let mut h = Fnv64::default();
        h.u64(key);
        for layer in coverage {
            h.bytes(layer.as_deref().unwrap_or(b"all shown"));
        }
        key = h.finish();
    }
    let path = cache_file(cache_dir, key);
    if path.exists() {
        match read_cache(&path, key) {
            Ok(image) if image.layers.len() == eyes.len() && (image.width, image.height) == size => {
                let total: usize = image.layers.iter().map(Vec::len).sum();
                progress(Progress { done: total, total, rays: 0, elapsed: std::time::Duration::ZERO });
                return Ok(image);
            }
            Ok(_) => log::warn!("{}: reference cache file does not match its key; tracing again", path.display()),
            Err(why) => log::warn!("{}: unusable reference cache file ({why}); tracing again", path.display()),
        }
    }
    let image = super::trace_visible(scene, eyes, size, settings, coverage, progress)?;
    write_cache(&path, key, &image)?;
    Ok(image)
}

/// Writes `image` under `key` to `path` (through a temporary file and a rename, so a
/// reader never sees half a file).
pub fn write_cache(path: &Path, key: u64, image: &ReferenceImage) -> Result<()> {
    let output = |message: String| Error::Output { path: path.to_path_buf(), message };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| output(format!("cannot create the cache directory: {e}")))?;
    }
    let bytes = encode(key, image);
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, &bytes).map_err(|e| output(format!("cannot write the reference cache: {e}")))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        std::fs::remove_file(&tmp).ok();
        output(format!("cannot move the reference cache into place: {e}"))
    })
}

/// Reads the image stored under `key` at `path`; the error says why it is unusable.
pub fn read_cache(path: &Path, key: u64) -> std::result::Result<ReferenceImage, UnusableCache> {
    let bytes = vrao_render::files::read_regular_file(path, vrao_render::files::MAX_FILE_BYTES)
        .map_err(|e| UnusableCache(e.problem.to_string()))?;
    decode(&bytes, key)
}

/// Why a reference cache file cannot be used (whoever wanted it traces again).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct UnusableCache(pub String);

impl From<&str> for UnusableCache {
    fn from(why: &str) -> UnusableCache {
        UnusableCache(why.to_string())
    }
}

impl From<String> for UnusableCache {
    fn from(why: String) -> UnusableCache {
        UnusableCache(why)
    }
}

fn encode(key: u64, image: &ReferenceImage) -> Vec<u8> {
    let (gw, gh) = image.grid_size();
    let cells: usize = image.layers.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(HEADER_BYTES + cells * PIXEL_BYTES + 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
    for v in [image.width, image.height, image.stride, image.layers.len() as u32, gw, gh] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let s = &image.stats;
    out.extend_from_slice(&s.rays.to_le_bytes());
    for v in [s.seconds, s.build_seconds, s.rays_per_second, s.noise] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&s.hit_pixels.to_le_bytes());
    for p in image.layers.iter().flatten() {
        out.push(p.hit as u8);
        let scalars = [p.depth, p.ao, p.ao_falloff, p.ao_std_error];
        let light = p.environment_visible.iter().chain(&p.bounce).chain(&p.unoccluded);
        for v in scalars.iter().chain(light).chain(&p.ambient_std_error).chain(&p.bounce_std_error) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let mut h = Fnv64::default();
    h.bytes(&out);
    out.extend_from_slice(&h.finish().to_le_bytes());
    out
}

/// A cursor over the file's bytes.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> std::result::Result<[u8; N], UnusableCache> {
        if self.bytes.len() < N {
            return Err("truncated".into());
        }
        let (head, rest) = self.bytes.split_at(N);
        self.bytes = rest;
        Ok(head.try_into().expect("split at N"))
    }
    fn u32(&mut self) -> std::result::Result<u32, UnusableCache> {
        self.take().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> std::result::Result<u64, UnusableCache> {
        self.take().map(u64::from_le_bytes)
    }
    fn f32(&mut self) -> std::result::Result<f32, UnusableCache> {
        self.take().map(f32::from_le_bytes)
    }
    fn f64(&mut self) -> std::result::Result<f64, UnusableCache> {
        self.take().map(f64::from_le_bytes)
    }
    fn f32x3(&mut self) -> std::result::Result<[f32; 3], UnusableCache> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }
    fn f32x4(&mut self) -> std::result::Result<[f32; 4], UnusableCache> {
        Ok([self.f32()?, self.f32()?, self.f32()?, self.f32()?])
    }
}

fn decode(bytes: &[u8], key: u64) -> std::result::Result<ReferenceImage, UnusableCache> {
    if bytes.len() < HEADER_BYTES + 8 {
        return Err(format!("truncated ({} bytes)", bytes.len()).into());
    }
    let (body, checksum) = bytes.split_at(bytes.len() - 8);
    let mut h = Fnv64::default();
    h.bytes(body);
    if h.finish() != u64::from_le_bytes(checksum.try_into().expect("8 bytes")) {
        return Err("checksum mismatch (truncated or corrupt)".into());
    }
    let mut r = Reader { bytes: body };
    if &r.take::<8>()? != MAGIC {
        return Err("not a reference cache file".into());
    }
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(format!("format version {version}, expected {FORMAT_VERSION}").into());
    }
    if r.u64()? != key {
        return Err("written for other inputs".into());
    }
    let (width, height, stride, layer_count, gw, gh) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?);
    if width == 0 || height == 0 || stride == 0 || grid_size((width, height), stride) != (gw, gh) {
        return Err(format!("inconsistent size {width}×{height} / {stride} with grid {gw}×{gh}").into());
    }
    let cells = gw as u64 * gh as u64;
    let expected = HEADER_BYTES as u64 + layer_count as u64 * cells * PIXEL_BYTES as u64;
    if body.len() as u64 != expected {
        return Err(format!("{} bytes where {expected} were expected", body.len()).into());
    }
    let rays = r.u64()?;
    let (seconds, build_seconds, rays_per_second, noise) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
    let hit_pixels = r.u64()?;
    let mut layers = Vec::with_capacity(layer_count as usize);
    for _ in 0..layer_count {
        let mut layer = Vec::with_capacity(cells as usize);
        for _ in 0..cells {
            let hit = match r.take::<1>()?[0] {
                0 => false,
                1 => true,
                other => return Err(format!("bad hit flag {other}").into()),
            };
            layer.push(ReferencePixel {
                hit,
                depth: r.f32()?,
                ao: r.f32()?,
                ao_falloff: r.f32()?,
                ao_std_error: r.f32()?,
                environment_visible: r.f32x3()?,
                bounce: r.f32x3()?,
                unoccluded: r.f32x3()?,
                ambient_std_error: r.f32x4()?,
                bounce_std_error: r.f32x4()?,
            });
        }
        layers.push(layer);
    }
    let stats = ReferenceStats { rays, seconds, build_seconds, rays_per_second, noise, hit_pixels, from_cache: true };
    Ok(ReferenceImage { width, height, stride, layers, stats })
}

/// Where reference images are cached between runs: `$XDG_CACHE_HOME/vrao/reference`,
/// else `~/.cache/vrao/reference`, else under the temporary directory.
pub fn default_cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("vrao").join("reference")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_its_published_test_vectors() {
        let hash = |s: &[u8]| {
            let mut h = Fnv64::default();
            h.bytes(s);
            h.finish()
        };
        assert_eq!(hash(b""), 0xcbf29ce484222325);
        assert_eq!(hash(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(hash(b"foobar"), 0x85944171f73967e8);
    }

    fn sample_image() -> ReferenceImage {
        let pixel = |k: usize| ReferencePixel {
            hit: !k.is_multiple_of(3),
            depth: k as f32 * 0.5,
            ao: 1.0 / (k as f32 + 1.0),
            ao_falloff: 0.75,
            ao_std_error: 0.01 * k as f32,
            environment_visible: [1.0, 2.0, k as f32],
            bounce: [f32::MIN_POSITIVE, 0.0, -0.0],
            unoccluded: [3.0, 2.0, 1.0],
            ambient_std_error: [0.1, 0.2, 0.3, k as f32],
            bounce_std_error: [0.0, 0.5, 0.25, 0.125],
        };
        ReferenceImage {
            width: 5,
            height: 3,
            stride: 2,
            layers: vec![(0..6).map(pixel).collect(), (6..12).map(pixel).collect()],
            stats: ReferenceStats {
                rays: 1234,
                seconds: 0.5,
                build_seconds: 0.1,
                rays_per_second: 2468.0,
                noise: 0.003,
                hit_pixels: 8,
                from_cache: false,
            },
        }
    }

    #[test]
    fn encoding_round_trips_bit_for_bit_and_rejects_damage() {
        let image = sample_image();
        let bytes = encode(42, &image);
        let back = decode(&bytes, 42).unwrap();
        assert!(back.stats.from_cache);
        assert_eq!(back.layers, image.layers);
        assert_eq!(ReferenceStats { from_cache: false, ..back.stats }, image.stats);
        assert_eq!((back.width, back.height, back.stride), (5, 3, 2));
        // -0.0 and 0.0 compare equal; the bits must survive too.
        assert_eq!(back.layers[0][0].bounce[2].to_bits(), (-0.0f32).to_bits());

        assert!(decode(&bytes, 43).unwrap_err().0.contains("other inputs"));
        for cut in [0, 7, HEADER_BYTES, bytes.len() - 1] {
            assert!(decode(&bytes[..cut], 42).is_err(), "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        flipped[HEADER_BYTES + 3] ^= 1;
        assert!(decode(&flipped, 42).unwrap_err().0.contains("checksum"));
    }
}
