//! Entry points for fuzzing the loaders on bytes (the cargo-fuzz targets in `fuzz/` and
//! the bounded mutation run in `tests/fuzz_loaders.rs` both use them).
//!
//! The loaders read files (an OBJ names its MTL, a scene file names its OBJ or glTF, a
//! glTF its buffer), so each input is written next to fixed, valid companions in a
//! scratch directory and loaded through [`Scene::load`], the path users take. Beside them
//! lie what a path must never be read as: `zero.bin` (a symlink to `/dev/zero`),
//! `pipe.bin` (a FIFO), `folder.png` (a directory) and, one level up, `vrao-fuzz-outside.bin`; the
//! mutation tokens name them (and `../` and absolute paths), so mutated inputs reach them.
//! Any result is fine, `Ok` or `Err`; a panic, a hang, a NaN or a value beyond the
//! renderer's bounds in a loaded scene is a bug.

use crate::error::Result;
use std::path::Path;
use vrao_render::scene::Scene;

/// Which loader the bytes feed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The bytes are an OBJ file (its `mtllib fuzz.mtl` finds a valid library).
    Obj,
    /// The bytes are the MTL library of a valid OBJ.
    Mtl,
    /// The bytes are a TOML scene file (`obj = "fuzz.obj"` finds a valid mesh).
    SceneFile,
    /// The bytes are a glTF file (`.gltf` JSON, or a `.glb` container: the loader reads
    /// the content, not the extension).
    Gltf,
}

impl Target {
    /// Every target, for loops over all of them.
    pub const ALL: [Target; 4] = [Target::Obj, Target::Mtl, Target::SceneFile, Target::Gltf];

    /// The file extension the fuzzed bytes are written with.
    pub fn extension(self) -> &'static str {
        match self {
            Target::Obj => "obj",
            Target::Mtl => "mtl",
            Target::SceneFile => "toml",
            Target::Gltf => "gltf",
        }
    }
}

/// A small valid OBJ using the library `fuzz.mtl`.
pub const VALID_OBJ: &str = "mtllib fuzz.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nusemtl red\nf 1/1/1 2/2/1 3/3/1\nf 2 4 3\n";
/// A valid MTL defining the material `red`.
pub const VALID_MTL: &str = "newmtl red\nKd 0.8 0.1 0.1\nKe 0 0 0\n";
/// A valid scene file placing `fuzz.gltf` three times, one of them moving (a scale key of
/// 0 hides it while it holds).
pub const VALID_SCENE_GLTF: &str = "[[mesh]]\ngltf = \"fuzz.gltf\"\n\n[[mesh]]\ngltf = \"fuzz.gltf\"\ntranslate = [2, 0, 0]\n\n[[mesh]]\ngltf = \"fuzz.gltf\"\nanimation = { keys = [{ t = 0, translate = [0, 0, 0], scale = 1 }, { t = 1, translate = [0, 1, 0], scale = 0 }] }\n\n[head]\neye = [0, 1, 4]\nlook_at = [0, 0, 0]\n";

/// A valid `.gltf` whose buffer is the file `fuzz.bin` beside it (the bytes of
/// [`VALID_GLTF`]'s data URI), with a second instance of its mesh under a node of scale 0
/// (hidden, one warning) and a scale animation to 0.
pub const VALID_GLTF_FILES: &str = "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,2]}],\"nodes\":[{\"translation\":[0,0,-1],\"children\":[1]},{\"mesh\":0,\"scale\":[2,2,2]},{\"mesh\":0,\"scale\":[0,0,0]}],\"meshes\":[{\"name\":\"tri\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},{\"bufferView\":2,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},{\"buffer\":0,\"byteOffset\":44,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":52,\"byteLength\":24}],\"buffers\":[{\"byteLength\":76,\"uri\":\"fuzz.bin\"}],\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"scale\"}}],\"samplers\":[{\"input\":2,\"output\":3,\"interpolation\":\"LINEAR\"}]}]}";

/// A valid scene file placing `fuzz.obj`.
pub const VALID_SCENE: &str = "name = \"fuzz\"\n\n[[mesh]]\nobj = \"fuzz.obj\"\ntranslate = [0, 0, -1]\nscale = 2\n\n[[light]]\ntype = \"directional\"\ndirection = [0, -1, -1]\nintensity = 2\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 5\n\n[environment]\nsky = \"default\"\n\n[head]\npath = [{ t = 0, eye = [0, 1, 2], look_at = [0, 0, 0] }, { t = 1, eye = [1, 1, 2], look_at = [0, 0, 0] }]\n";

/// A small valid `.gltf`: an indexed triangle under a moving parent, a masked material and
/// a spot light, its buffer a data URI.
pub const VALID_GLTF: &str = "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_lights_punctual\"],\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"intensity\":5,\"spot\":{\"innerConeAngle\":0.2,\"outerConeAngle\":0.5}}]}},\"scene\":0,\"scenes\":[{\"nodes\":[0,2]}],\"nodes\":[{\"translation\":[0,0,-1],\"children\":[1]},{\"mesh\":0,\"scale\":[2,2,2]},{\"translation\":[0,2,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}],\"meshes\":[{\"name\":\"tri\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}],\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.1,0.1,0.5]},\"alphaMode\":\"MASK\",\"alphaCutoff\":0.4,\"emissiveFactor\":[0,0,0]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},{\"bufferView\":2,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},{\"buffer\":0,\"byteOffset\":44,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":52,\"byteLength\":24}],\"buffers\":[{\"byteLength\":76,\"uri\":\"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAA==\"}],\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}],\"samplers\":[{\"input\":2,\"output\":3,\"interpolation\":\"LINEAR\"}]}]}";

/// Writes `data` as the `target` file beside valid companions in `dir` and loads it.
pub fn load_bytes(target: Target, data: &[u8], dir: &Path) -> Result<Scene> {
    let write = |name: &str, bytes: &[u8]| {
        std::fs::write(dir.join(name), bytes)
            .map_err(|e| crate::error::Error::Output { path: dir.join(name), message: e.to_string() })
    };
    write("fuzz.obj", if target == Target::Obj { data } else { VALID_OBJ.as_bytes() })?;
    write("fuzz.mtl", if target == Target::Mtl { data } else { VALID_MTL.as_bytes() })?;
    write("fuzz.toml", if target == Target::SceneFile { data } else { VALID_SCENE.as_bytes() })?;
    write("fuzz.gltf", if target == Target::Gltf { data } else { VALID_GLTF.as_bytes() })?;
    write("fuzz.bin", &fuzz_bin())?;
    special_companions(dir);
    let entry = match target {
        Target::SceneFile => "fuzz.toml",
        Target::Gltf => "fuzz.gltf",
        _ => "fuzz.obj",
    };
    let scene = Scene::load(dir.join(entry).to_str().unwrap_or_default())?;
    check_finite(&scene);
    Ok(scene)
}

/// The bytes of [`VALID_GLTF`]'s buffer, for [`VALID_GLTF_FILES`]'s `fuzz.bin`.
fn fuzz_bin() -> Vec<u8> {
    let start = VALID_GLTF.find("base64,").map_or(0, |i| i + 7);
    let end = VALID_GLTF[start..].find('"').map_or(start, |i| start + i);
    #[cfg(feature = "gltf")]
    return vrao_render::scene::gltf::decode_base64(&VALID_GLTF[start..end]).unwrap_or_default();
    #[cfg(not(feature = "gltf"))]
    return VALID_GLTF.as_bytes()[start..end].to_vec();
}

/// What a path named in an input must never be read as (made once per folder): a symlink
/// to `/dev/zero`, a FIFO (opening it would block), a directory named like an image, and
/// a file outside the input's folder.
fn special_companions(dir: &Path) {
    let _ = std::fs::create_dir_all(dir.join("folder.png"));
    if let Some(parent) = dir.parent() {
        if !parent.join("vrao-fuzz-outside.bin").exists() {
            let _ = std::fs::write(parent.join("vrao-fuzz-outside.bin"), fuzz_bin());
        }
    }
    #[cfg(unix)]
    {
        let zero = dir.join("zero.bin");
        if std::fs::symlink_metadata(&zero).is_err() {
            let _ = std::os::unix::fs::symlink("/dev/zero", &zero);
        }
        let link = dir.join("link.bin");
        if std::fs::symlink_metadata(&link).is_err() {
            let _ = std::os::unix::fs::symlink("../vrao-fuzz-outside.bin", &link);
        }
        let pipe = dir.join("pipe.bin");
        if std::fs::symlink_metadata(&pipe).is_err() {
            let _ = std::process::Command::new("mkfifo").arg(&pipe).status();
        }
    }
}

/// A loaded scene never holds a non-finite number: the loaders reject or drop them.
fn check_finite(scene: &Scene) {
    for mesh in &scene.meshes {
        assert!(mesh.origin.is_finite(), "mesh {} origin {}", mesh.name, mesh.origin);
        assert!(mesh.positions.iter().all(|p| p.is_finite()), "mesh {} has a non-finite position", mesh.name);
        assert!(mesh.normals.iter().all(|n| n.is_finite()), "mesh {} has a non-finite normal", mesh.name);
        assert!(mesh.uvs.iter().all(|t| t.is_finite()), "mesh {} has a non-finite uv", mesh.name);
        assert!(
            mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()),
            "mesh {} index out of range",
            mesh.name
        );
        assert!(mesh.material < scene.materials.len(), "mesh {} material out of range", mesh.name);
        // Finite is not enough: nothing beyond what the renderer can draw (limits.rs).
        if mesh.node.is_none() {
            assert_eq!(vrao_render::scene::limits::mesh_trouble(mesh), None, "mesh {} is out of range", mesh.name);
        }
    }
    for m in &scene.materials {
        assert!(m.diffuse.is_finite() && m.emissive.is_finite(), "material {} is not finite", m.name);
        let brightest = m.emissive.max_element() as f64;
        assert!(brightest <= vrao_render::scene::limits::RADIANCE_MAX, "material {} emits {brightest}", m.name);
    }
    for t in [0.0, 0.5, 1e6] {
        assert!(scene.node_transforms(t).iter().all(|m| m.is_finite()), "a node transform is not finite at {t}");
    }
    // Moving meshes and the head stay where static geometry may be; the scene within budget.
    use vrao_render::scene::limits;
    assert_eq!(limits::motion_trouble(&scene.meshes, &scene.nodes), None, "a moving mesh is out of range");
    assert_eq!(limits::head_trouble(&scene.head), None, "the head is out of range");
    assert_eq!(limits::GeometryBudget::of(&scene.meshes).trouble(), None, "over the triangle budget");
}

/// Tokens a mutation inserts: what OBJ, MTL and TOML parsers trip over.
const TOKENS: &[&[u8]] = &[
    b"nan",
    b"inf",
    b"-inf",
    b"1e39",
    b"-1e39",
    b"3e38",
    b"1e300",
    b"1e-300",
    b"1e-45",
    b"0",
    b"-1",
    b"-2147483649",
    b"4294967296",
    b"18446744073709551616",
    b"\n",
    b"\r\n",
    b" ",
    b"/",
    b"//",
    b"#",
    b"\\",
    b"\"",
    b"'",
    b"[",
    b"]",
    b"{",
    b"}",
    b"=",
    b",",
    b".",
    b"f ",
    b"v ",
    b"vt ",
    b"vn ",
    b"o ",
    b"g ",
    b"s ",
    b"usemtl ",
    b"mtllib ",
    b"newmtl ",
    b"Kd ",
    b"Ke ",
    b"map_Kd ",
    b"map_d ",
    b"d ",
    b"Tr ",
    b"\"mode\":",
    b"\"count\":",
    b"\"byteOffset\":",
    b"\"byteStride\":",
    b"\"children\":[0]",
    b"\"matrix\":",
    b"\"CUBICSPLINE\"",
    b"\"uri\":\"zero.bin\"",
    b"\"uri\":\"pipe.bin\"",
    b"\"uri\":\"folder.png\"",
    b"\"uri\":\"link.bin\"",
    b"\"uri\":\"../vrao-fuzz-outside.bin\"",
    b"\"uri\":\"/dev/zero\"",
    b"\"images\":[{\"uri\":\"pipe.bin\"}],",
    b"\"scale\":[0,0,0]",
    b"\"scale\":[1e-30,1e-30,1e-30]",
    b"\"translation\":[1e30,0,0]",
    b"\"matrix\":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1]",
    b"1e30",
    b"-3e38",
    b"../",
    b"zero.bin",
    b"pipe.bin",
    b"folder.png",
    b"/dev/zero",
    b"gltf = \"fuzz.gltf\"\n",
    b"obj = \"pipe.bin\"\n",
    b"mtllib zero.bin\n",
    b"map_Kd pipe.bin\n",
    b"[[mesh]]\ngltf = \"fuzz.gltf\"\n[[mesh]]\ngltf = \"fuzz.gltf\"\n[[mesh]]\ngltf = \"fuzz.gltf\"\n",
    b"animation = { keys = [{ t = 0, scale = 0 }, { t = 1, translate = [1e30, 0, 0] }] }\n",
    b"scale = 0",
    b"4294967295",
    b"1e300",
    b"[[mesh]]\n",
    b"[[light]]\n",
    b"[head]\n",
    b"[environment]\n",
    b"obj = ",
    b"type = ",
    b"path = ",
    b"t = ",
    b"\xff",
    b"\x00",
    b"\xe2\x80\xa8",
];

/// A small deterministic generator (xorshift64*), so a failing run can be replayed.
pub struct Mutator {
    state: u64,
}

impl Mutator {
    /// A generator started from `seed` (any value; the same seed gives the same mutations).
    pub fn new(seed: u64) -> Mutator {
        Mutator { state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1 }
    }

    fn next(&mut self) -> u64 {
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        self.state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    /// Applies one to four random edits: flip a byte, insert a token, delete or
    /// duplicate a range, or replace a number-like run with a token.
    pub fn mutate(&mut self, data: &mut Vec<u8>) {
        for _ in 0..1 + self.below(4) {
            let at = self.below(data.len() + 1);
            match self.below(5) {
                0 if !data.is_empty() => {
                    let i = self.below(data.len());
                    data[i] ^= 1 << self.below(8);
                }
                1 => {
                    let token = TOKENS[self.below(TOKENS.len())];
                    data.splice(at..at, token.iter().copied());
                }
                2 if !data.is_empty() => {
                    let end = (at + 1 + self.below(16)).min(data.len());
                    data.drain(at.min(end)..end);
                }
                3 if !data.is_empty() && data.len() < 1 << 16 => {
                    let start = self.below(data.len());
                    let end = (start + 1 + self.below(64)).min(data.len());
                    let copy = data[start..end].to_vec();
                    let at = self.below(data.len() + 1);
                    data.splice(at..at, copy);
                }
                _ => {
                    // Replace the number (or word) at `at` by a token.
                    let start = at.min(data.len());
                    let end =
                        data[start..].iter().position(|b| b.is_ascii_whitespace()).map_or(data.len(), |k| start + k);
                    let token = TOKENS[self.below(TOKENS.len())];
                    data.splice(start..end, token.iter().copied());
                }
            }
        }
    }
}
