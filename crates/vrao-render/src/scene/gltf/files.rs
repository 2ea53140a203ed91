//! The bytes of a glTF and of the files it names: the GLB container, buffers and data or
//! file URIs. A file URI names a regular file inside the glTF's folder (or below it):
//! `..` that leaves the folder, an absolute path and a symlink that resolves outside it
//! are refused naming the URI, as is anything that is not a regular file.

use super::MAX_FILE_BYTES;
use crate::files::{check_regular_file, read_regular_file, FileProblem};
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;
use vrao_ao::{Error, Result};

/// Reads `file` (the glTF itself or a file it names) as a regular file of at most
/// [`MAX_FILE_BYTES`]. Errors name `gltf`, the file the user gave, and `file` when it differs.
pub(super) fn read_bounded(gltf: &Path, file: &Path) -> Result<Vec<u8>> {
    let what = if gltf == file { String::new() } else { format!("{}: ", file.display()) };
    read_regular_file(file, MAX_FILE_BYTES).map_err(|e| Error::in_file(gltf, format!("{what}{}", e.problem)))
}

/// The JSON chunk and the optional BIN chunk of a GLB container, checked here (the
/// crate's parser trusts the header's lengths).
pub(super) fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let bad = |message: String| Error::in_file(path, message);
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(bad(format!("truncated .glb: {} bytes, shorter than the 12-byte header", bytes.len())));
    };
    if version != 2 {
        return Err(bad(format!(".glb container version {version}; vrao reads glTF 2.0 (version 2)")));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(bad(format!("truncated .glb: the header says {length} bytes, the file has {}", bytes.len())));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (Some(chunk_length), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(bad(format!("truncated .glb: chunk header at byte {at} runs past the end")));
        };
        let start = at + 8;
        let end = start.checked_add(chunk_length as usize).filter(|&e| e <= length).ok_or_else(|| {
            bad(format!("truncated .glb: chunk at byte {at} says {chunk_length} bytes, past the end ({length})"))
        })?;
        chunks.push((kind, &bytes[start..end]));
        at = end;
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => Ok((json, chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1))),
        _ => Err(bad("not a valid .glb: the first chunk is not JSON".into())),
    }
}

/// The bytes of every buffer: the GLB's BIN chunk, a data URI or a file beside the glTF.
/// Buffers naming one URI share one read of it (eight buffers naming one large file
/// read it once, not eight times).
pub(super) fn load_buffers(
    path: &Path,
    document: &::gltf::Document,
    bin: Option<Vec<u8>>,
) -> Result<Vec<Arc<Vec<u8>>>> {
    let mut buffers = Vec::new();
    let bin = bin.map(Arc::new);
    let mut read: HashMap<&str, Arc<Vec<u8>>> = HashMap::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            ::gltf::buffer::Source::Bin => bin.clone().ok_or_else(|| {
                Error::in_file(path, format!("buffer {i} refers to the .glb's binary chunk, which is missing"))
            })?,
            ::gltf::buffer::Source::Uri(uri) => match read.get(uri) {
                Some(bytes) => bytes.clone(),
                None => {
                    let bytes = resolve_uri(path, uri).map_err(|m| Error::in_file(path, format!("buffer {i}: {m}")))?;
                    read.entry(uri).or_insert(Arc::new(bytes)).clone()
                }
            },
        };
        if data.len() < buffer.length() {
            let message = format!("buffer {i} has {} bytes, the file says {}", data.len(), buffer.length());
            return Err(Error::in_file(path, message));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The bytes a URI names: a base64 data URI, or a file relative to the glTF's folder.
pub(super) fn resolve_uri(path: &Path, uri: &str) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest.split_once(',').ok_or("data URI without a ',' before its data")?;
        if !header.ends_with(";base64") {
            return Err("data URI is not base64 (';base64,' expected)".into());
        }
        if payload.len() as u64 > MAX_FILE_BYTES / 3 * 4 {
            return Err(format!("data URI of {} characters, over vrao's limit", payload.len()));
        }
        return decode_base64(payload).ok_or_else(|| "data URI holds invalid base64".to_string());
    }
    if uri.contains("://") {
        return Err(format!("URI '{uri}' is not a file beside the glTF (vrao reads no network)"));
    }
    let relative = percent_decode(uri).ok_or_else(|| format!("URI '{uri}' has a bad %-escape"))?;
    if !stays_inside(&relative) {
        return Err(format!("URI '{uri}' leaves the glTF's folder (vrao reads only files in it and below it)"));
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    let file = folder.join(&relative);
    match check_regular_file(&file) {
        Ok(_) => {}
        Err(e) if matches!(e.problem, FileProblem::Missing) => {
            return Err(format!("file '{uri}' not found (looked for {})", file.display()));
        }
        Err(e) => return Err(format!("file '{uri}' {}", e.problem)),
    }
    // A symlink may point anywhere: where it resolves must be inside the folder too.
    let inside = |f: &Path| -> std::io::Result<bool> {
        let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
        Ok(f.canonicalize()?.starts_with(folder.canonicalize()?))
    };
    match inside(&file) {
        Ok(true) => {}
        Ok(false) => {
            return Err(format!(
                "URI '{uri}' leaves the glTF's folder (a symlink to a file outside it; vrao reads only files in it \
                 and below it)"
            ))
        }
        Err(e) => return Err(format!("file '{uri}': cannot read: {e}")),
    }
    read_bounded(path, &file).map_err(|e| match e {
        Error::Input { message, .. } => message,
        other => other.to_string(),
    })
}

/// Whether the relative path `relative` stays inside the folder it is relative to: not
/// absolute, and no `..` climbs above where it started.
fn stays_inside(relative: &Path) -> bool {
    let mut depth = 0usize;
    for component in relative.components() {
        match component {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => return false,
            },
            Component::RootDir | Component::Prefix(_) => return false,
        }
    }
    true
}

/// Standard base64 (RFC 4648) with optional padding; `None` for any other character.
pub fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let digit = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=').as_bytes();
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    for chunk in body.chunks(4) {
        let mut bits = 0u32;
        for &c in chunk {
            bits = (bits << 6) | digit(c)?;
        }
        bits <<= 6 * (4 - chunk.len()) as u32;
        let bytes = bits.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// `%XX` escapes decoded (URIs in glTF are percent-encoded); `None` for a broken escape.
fn percent_decode(uri: &str) -> Option<PathBuf> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("aGk=").unwrap(), b"hi");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("aGk*").is_none());
        assert!(decode_base64("a").is_none());
        assert!(decode_base64("aG===").is_none());
    }

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("my%20file.bin").unwrap(), PathBuf::from("my file.bin"));
        assert!(percent_decode("bad%2").is_none());
        assert!(percent_decode("bad%zz").is_none());
    }

    fn scratch(name: &str) -> crate::test_dir::TestDir {
        crate::test_dir::TestDir::new(&format!("gltf-files-{name}"))
    }

    #[test]
    fn uris_stay_in_the_gltfs_folder() {
        let outside = scratch("uri-outside");
        std::fs::write(outside.join("x.bin"), b"secret").unwrap();
        let folder = scratch("uri");
        let dir = folder.join("model");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("in.bin"), b"bytes").unwrap();
        let gltf = dir.join("model.gltf");
        let read = |uri: &str| resolve_uri(&gltf, uri);
        assert_eq!(read("in.bin").unwrap(), b"bytes");
        assert_eq!(read("sub/../in.bin").unwrap(), b"bytes");
        assert_eq!(read("./sub/./../in.bin").unwrap(), b"bytes");
        let escape = format!("../../{}/x.bin", outside.file_name().unwrap().to_string_lossy());
        let absolute = outside.join("x.bin").display().to_string();
        for uri in [escape.as_str(), "sub/../../in.bin", "%2E%2E/model/in.bin", absolute.as_str()] {
            let e = read(uri).unwrap_err();
            assert_eq!(e, format!("URI '{uri}' leaves the glTF's folder (vrao reads only files in it and below it)"));
        }
        // A symlink in the folder that resolves outside it.
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(outside.join("x.bin"), dir.join("link.bin")).unwrap();
            let e = read("link.bin").unwrap_err();
            assert!(e.starts_with("URI 'link.bin' leaves the glTF's folder (a symlink"), "{e}");
            // One that stays inside is fine.
            std::os::unix::fs::symlink(dir.join("in.bin"), dir.join("sub/alias.bin")).unwrap();
            assert_eq!(read("sub/alias.bin").unwrap(), b"bytes");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_uri_naming_a_device_fifo_or_folder_says_what_it_is_at_once() {
        let dir = scratch("uri-special");
        let gltf = dir.join("model.gltf");
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
        std::os::unix::fs::symlink("/dev/urandom", dir.join("random.png")).unwrap();
        std::fs::create_dir(dir.join("textures")).unwrap();
        let fifo = std::process::Command::new("mkfifo").arg(dir.join("pipe.bin")).status().is_ok_and(|s| s.success());
        let started = std::time::Instant::now();
        let mut cases = vec![
            ("zero.bin", "file 'zero.bin' is a character device, not a regular file"),
            ("random.png", "file 'random.png' is a character device, not a regular file"),
            ("textures", "file 'textures' is a directory, not a regular file"),
        ];
        if fifo {
            cases.push(("pipe.bin", "file 'pipe.bin' is a FIFO (named pipe), not a regular file"));
        }
        for (uri, expected) in cases {
            assert_eq!(resolve_uri(&gltf, uri).unwrap_err(), expected);
        }
        let missing = resolve_uri(&gltf, "none.bin").unwrap_err();
        assert!(missing.starts_with("file 'none.bin' not found (looked for "), "{missing}");
        assert!(started.elapsed().as_secs() < 2, "refused without reading");
    }

    /// Standard base64 with padding (the tests' glTF buffers).
    fn base64(bytes: &[u8]) -> String {
        const DIGITS: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
            let bits = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
            for k in 0..4 {
                if k <= chunk.len() {
                    out.push(DIGITS[(bits >> (18 - 6 * k) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    /// A `.gltf` of one triangle (mesh 0) at node 0, whose other JSON members are `node`,
    /// and with `animation` (a path and its two keys' values, at t = 0 and 1) on node 0.
    fn triangle_gltf(node: &str, animation: Option<(&str, [[f32; 3]; 2])>) -> String {
        let mut floats: Vec<f32> = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let values = animation.map_or([[0.0; 3]; 2], |a| a.1);
        floats.extend(values.iter().flatten());
        let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        let animations = match animation {
            Some((path, _)) => format!(
                r#","animations":[{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"{path}"}}}}],"samplers":[{{"input":1,"output":2}}]}}]"#
            ),
            None => String::new(),
        };
        let comma = if node.is_empty() { "" } else { "," };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0{comma}{node}}}],"meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}}}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}},{{"bufferView":2,"componentType":5126,"count":2,"type":"VEC3"}}],"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":8}},{{"buffer":0,"byteOffset":44,"byteLength":24}}],"buffers":[{{"byteLength":68,"uri":"data:application/octet-stream;base64,{}"}}]{animations}}}"#,
            base64(&bytes)
        )
    }

    fn load_text(dir: &Path, name: &str, text: &str) -> Result<crate::scene::Scene> {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        crate::scene::Scene::load(path.to_str().unwrap())
    }

    #[test]
    fn far_and_huge_animation_keys_and_node_transforms_are_refused_naming_the_element() {
        let dir = scratch("far-keys");
        assert!(
            load_text(&dir, "ok.gltf", &triangle_gltf("", Some(("translation", [[0.0; 3], [2.0, 0.0, 0.0]])))).is_ok()
        );
        type Case<'a> = (&'a str, Option<(&'a str, [[f32; 3]; 2])>, &'a str);
        let cases: [Case; 8] = [
            (
                "",
                Some(("translation", [[0.0; 3], [1e30, 0.0, 0.0]])),
                "animation 0 channel 0 output: key 2 translation 1e30 m is farther than 1e6 m",
            ),
            ("", Some(("translation", [[0.0; 3], [0.0, 3e38, 0.0]])), "key 2 translation 3e38 m is farther"),
            (
                "",
                Some(("scale", [[1.0; 3], [1e30, 1.0, 1.0]])),
                "animation 0 channel 0 output: key 2 scale 1e30 is larger than 1e6",
            ),
            ("", Some(("scale", [[1e-30, 1.0, 1.0], [1.0; 3]])), "key 1 scale 1e-30 is smaller than 1e-6 and not 0"),
            (r#""translation":[1e30,0,0]"#, None, "node 0: translation 1e30 m is farther than 1e6 m"),
            (r#""scale":[1,1e30,1]"#, None, "node 0: scale 1e30 is larger than 1e6"),
            (r#""matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,-5e6,1]"#, None, "node 0: translation -5e6 m is farther"),
            // Each key in range, the product not: reached over the animation.
            (r#""children":[]"#, Some(("translation", [[0.0; 3], [9e5, 0.0, 0.0]])), ""),
        ];
        for (i, (node, animation, expected)) in cases.into_iter().enumerate() {
            let result = load_text(&dir, &format!("case{i}.gltf"), &triangle_gltf(node, animation));
            if expected.is_empty() {
                assert!(result.is_ok(), "case {i}: {:?}", result.err());
                continue;
            }
            let e = result.err().unwrap_or_else(|| panic!("case {i} loads")).to_string();
            assert!(
                e.starts_with(&dir.join(format!("case{i}.gltf")).display().to_string()) && e.contains(expected),
                "case {i}: {e}"
            );
        }
    }

    #[test]
    fn a_camera_carried_beyond_the_far_bound_is_refused() {
        // Each node in range, the chain not: the camera (the head) 1.8e6 m out.
        let dir = scratch("far-camera");
        let camera = r#""cameras":[{"type":"perspective","perspective":{"yfov":1,"znear":0.1}}],"asset""#;
        let chain = |x: &str| {
            triangle_gltf(&format!(r#""translation":[{x},0,0],"children":[1]"#), None)
                .replace(r#"}],"meshes""#, &format!(r#"}},{{"camera":0,"translation":[{x},0,0]}}],"meshes""#))
                .replace(r#""asset""#, camera)
        };
        assert!(load_text(&dir, "near.gltf", &chain("4e5")).is_ok());
        let e = load_text(&dir, "far.gltf", &chain("9e5")).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.ends_with("far.gltf: the head (camera) position 1.8e6 m is farther than 1e6 m from the origin"),
            "{e}"
        );
    }

    #[test]
    fn a_tangent_along_the_normal_or_zero_gives_way_to_the_derived_frame_with_one_warning() {
        // Issue 50: a TANGENT parallel to the NORMAL striped the shading.
        let dir = scratch("tangents");
        let gltf = |tangent: [f32; 4]| {
            let mut floats: Vec<f32> = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
            floats.extend([0.0, 0.0, 1.0].repeat(3));
            floats.extend(tangent.repeat(3));
            let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
            format!(
                r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TANGENT":2}}}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC4"}}],"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},{{"buffer":0,"byteOffset":72,"byteLength":48}}],"buffers":[{{"byteLength":120,"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
                base64(&bytes)
            )
        };
        let cases: [(&str, [f32; 4], bool); 5] = [
            ("along", [0.0, 0.0, 1.0, 1.0], true),
            ("zero", [0.0; 4], true),
            ("nearly", [0.005, 0.0, 1.0, 1.0], true),
            ("across", [1.0, 0.0, 0.0, 1.0], false),
            ("tilted", [1.0, 0.0, 0.5, -1.0], false),
        ];
        for (name, tangent, derived) in cases {
            let file = dir.join(format!("{name}.gltf"));
            std::fs::write(&file, gltf(tangent)).unwrap();
            let content = super::super::load_content(&file, 0).unwrap();
            let lines: Vec<&String> = content.warnings.iter().filter(|l| l.contains("TANGENT")).collect();
            let mesh = &content.meshes[0];
            if derived {
                assert_eq!(lines.len(), 1, "{name}: {:?}", content.warnings);
                assert!(
                    lines[0].contains("mesh 'tri' primitive 0 (vertex 0)") && lines[0].contains("derived"),
                    "{lines:?}"
                );
                assert!(mesh.tangents.is_empty(), "{name}: the shader derives the frame");
            } else {
                assert!(lines.is_empty(), "{name}: {lines:?}");
                assert_eq!(mesh.tangents.len(), 3, "{name}");
            }
        }
    }

    #[test]
    fn tiny_node_scales_hide_the_mesh_and_zero_scale_keys_keep_every_value_finite() {
        let dir = scratch("tiny");
        // A static node of scale 0, 1e-30, or a zero matrix: the file loads, its mesh
        // collapses to a point (not drawn).
        for (i, node) in
            [r#""scale":[0,0,0]"#, r#""scale":[1e-30,1e-30,1e-30]"#, r#""matrix":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1]"#]
                .into_iter()
                .enumerate()
        {
            let scene = load_text(&dir, &format!("hidden{i}.gltf"), &triangle_gltf(node, None)).unwrap();
            let mesh = &scene.meshes[0];
            let area = |m: &crate::scene::Mesh| {
                let [a, b, c] = [0, 1, 2].map(|k| m.positions[m.indices[k] as usize]);
                (b - a).cross(c - a).length()
            };
            assert!(area(mesh) == 0.0 && mesh.normals.iter().all(|n| n.is_finite()), "{node}: {mesh:?}");
        }
        // A scale key of exactly 0 (hiding the triangle at t = 1) loads; at every time
        // the transforms, the baked scene and the bounds stay finite.
        let scene = load_text(&dir, "shrink.gltf", &triangle_gltf("", Some(("scale", [[1.0; 3], [0.0; 3]])))).unwrap();
        for t in [0.0, 0.5, 0.999, 1.0, 2.0] {
            assert!(scene.node_transforms(t).iter().all(|m| m.is_finite()), "t = {t}");
            let still = scene.at_time(t);
            for m in &still.meshes {
                assert!(m.origin.is_finite() && m.positions.iter().chain(&m.normals).all(|v| v.is_finite()), "t = {t}");
            }
        }
        let bounds = scene.bounds();
        assert!(bounds.min.is_finite() && bounds.max.is_finite() && scene.suggested_ao_radius().is_finite());
    }

    #[test]
    fn a_texture_of_the_documented_largest_side_decodes_in_gltf_and_obj_alike() {
        // 16384 × 16384 (1 GiB as RGBA8) passed the side check and then failed with the
        // image crate's default "Memory limit exceeded" (512 MiB).
        use crate::scene::limits::MAX_TEXTURE_SIDE;
        use image::ImageEncoder;
        let png = |width: u32, height: u32| {
            // One colour (zeroed memory: the pages are never touched), small compressed.
            let grey = vec![0u8; width as usize * height as usize];
            let mut bytes = Vec::new();
            let encoder = image::codecs::png::PngEncoder::new_with_quality(
                &mut bytes,
                image::codecs::png::CompressionType::Fast,
                image::codecs::png::FilterType::NoFilter,
            );
            encoder.write_image(&grey, width, height, image::ExtendedColorType::L8).unwrap();
            bytes
        };
        let largest = png(MAX_TEXTURE_SIDE, MAX_TEXTURE_SIDE);
        let texture = super::super::decode_image(&largest).map_err(|p| p.0).unwrap();
        assert_eq!((texture.width, texture.height), (MAX_TEXTURE_SIDE, MAX_TEXTURE_SIDE));
        drop(texture);
        let dir = scratch("largest-texture");
        std::fs::write(dir.join("big.png"), &largest).unwrap();
        std::fs::write(dir.join("t.mtl"), "newmtl big\nmap_Kd big.png\n").unwrap();
        std::fs::write(dir.join("t.obj"), "mtllib t.mtl\nusemtl big\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let (_, materials) = crate::scene::obj::load_obj(&dir.join("t.obj"), 0).unwrap();
        let texture = materials[0].diffuse_texture.as_ref().unwrap();
        assert_eq!((texture.width, texture.height), (MAX_TEXTURE_SIDE, MAX_TEXTURE_SIDE));
        // One texel more is refused from the header, naming the limit, in both.
        let wider = png(MAX_TEXTURE_SIDE + 1, 1);
        let e = super::super::decode_image(&wider).map_err(|p| p.0).err().unwrap();
        assert_eq!(e, "16385×1 texels; vrao takes sides of 1 to 16384");
        std::fs::write(dir.join("big.png"), &wider).unwrap();
        let e = crate::scene::obj::load_obj(&dir.join("t.obj"), 0).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "big.png: cannot decode texture: 16385x1 texels; vrao takes at most 16384 per side (scale it down)"
            ),
            "{e}"
        );
    }

    #[test]
    fn glb_container_is_checked_before_parsing() {
        let p = Path::new("t.glb");
        let err = |bytes: &[u8]| split_glb(p, bytes).unwrap_err().to_string();
        assert!(err(b"glTF\x02\0\0").contains("shorter than the 12-byte header"));
        assert!(err(b"glTF\x01\0\0\0\x0c\0\0\0").contains("version 1"));
        assert!(err(b"glTF\x02\0\0\0\xff\0\0\0").contains("the header says 255 bytes, the file has 12"));
        let mut chunk = b"glTF\x02\0\0\0\x18\0\0\0".to_vec();
        chunk.extend_from_slice(&[100, 0, 0, 0]);
        chunk.extend_from_slice(b"JSON{}  ");
        assert!(err(&chunk).contains("says 100 bytes, past the end"), "{}", err(&chunk));
    }
}
