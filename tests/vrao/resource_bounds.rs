//! Every resource a glTF scene asks for is counted across the whole scene before the
//! work: draws (primitive instances), bytes read (one read per file, however many buffers
//! name it) and decoded images (one decode per source, however many slots name it).

use std::path::Path;
use std::time::{Duration, Instant};
use vrao::test_assets::gltf_write::encode_base64;
use vrao_render::scene::Scene;

/// A fresh, empty directory for one test's files, removed when the test passes.
fn temp_dir(name: &str) -> crate::common::TestDir {
    crate::common::temp_dir(&format!("bounds-{name}"))
}

/// One triangle (positions only, 36 bytes) in `buffers` buffers that all name `uri`, its
/// mesh drawn by `nodes` nodes; with `images` image entries naming `image_uri`, the mesh
/// has one primitive per image, each with a material showing it.
fn gltf(uri: &str, buffers: usize, nodes: usize, images: usize, image_uri: &str) -> String {
    let buffer_list: Vec<String> = (0..buffers).map(|_| format!(r#"{{"byteLength": 36, "uri": "{uri}"}}"#)).collect();
    let node_list: Vec<String> =
        (0..nodes).map(|i| format!(r#"{{"mesh": 0, "translation": [{}, 0, 0]}}"#, i % 7)).collect();
    let image_list: Vec<String> = (0..images).map(|_| format!(r#"{{"uri": "{image_uri}"}}"#)).collect();
    let texture_list: Vec<String> = (0..images).map(|i| format!(r#"{{"source": {i}}}"#)).collect();
    let material_list: Vec<String> = (0..images)
        .map(|i| format!(r#"{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": {i}}}}}}}"#))
        .collect();
    let primitives: Vec<String> = (0..images.max(1))
        .map(|i| {
            let material = if images > 0 { format!(r#", "material": {i}"#) } else { String::new() };
            format!(r#"{{"attributes": {{"POSITION": 0}}{material}}}"#)
        })
        .collect();
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [{nodes}]}}], "nodes": [{node_list}],
        "meshes": [{{"primitives": [{primitives}]}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}],
        "bufferViews": [{{"buffer": {last}, "byteLength": 36}}], "buffers": [{buffer_list}],
        "images": [{image_list}], "textures": [{texture_list}], "materials": [{material_list}]}}"#,
        nodes = (0..nodes).map(|i| i.to_string()).collect::<Vec<_>>().join(","),
        node_list = node_list.join(","),
        primitives = primitives.join(","),
        last = buffers - 1,
        buffer_list = buffer_list.join(","),
        image_list = image_list.join(","),
        texture_list = texture_list.join(","),
        material_list = material_list.join(","),
    )
}

fn triangle_bytes() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn load(dir: &Path, text: &str) -> vrao_ao::Result<Scene> {
    let path = dir.join("scene.gltf");
    std::fs::write(&path, text).unwrap();
    vrao_render::scene::gltf::load(&path)
}

#[test]
fn more_draws_than_the_bound_are_refused_in_one_line_before_the_work() {
    let dir = temp_dir("draws");
    let uri = format!("data:application/octet-stream;base64,{}", encode_base64(&triangle_bytes()));
    assert!(load(&dir, &gltf(&uri, 1, 1000, 0, "")).is_ok(), "a thousand instances of a mesh load");
    let started = Instant::now();
    let e = load(&dir, &gltf(&uri, 1, 70_000, 0, "")).unwrap_err().to_string();
    assert!(e.contains("65537 meshes") && e.contains("65536") && !e.contains('\n'), "{e}");
    assert!(e.starts_with(&dir.join("scene.gltf").display().to_string()), "{e}");
    assert!(started.elapsed() < Duration::from_secs(30), "refused in {:?}", started.elapsed());
}

#[test]
fn a_file_named_by_many_buffers_or_images_is_read_and_decoded_once() {
    let dir = temp_dir("shared");
    std::fs::write(dir.join("tri.bin"), triangle_bytes()).unwrap();
    let mut png = Vec::new();
    let image = image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 100, 50, 255]));
    image::DynamicImage::ImageRgba8(image)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.join("wall.png"), png).unwrap();
    let scene = load(&dir, &gltf("tri.bin", 8, 1, 64, "wall.png")).unwrap();
    let textures: Vec<_> = scene.materials.iter().filter_map(|m| m.diffuse_texture.as_ref()).collect();
    assert_eq!(textures.len(), 64, "every material names the image");
    assert!(
        textures.iter().all(|t| std::sync::Arc::ptr_eq(&t.rgba8, &textures[0].rgba8)),
        "64 image entries naming one file share one decoded image"
    );
}

#[test]
fn a_byte_order_mark_is_read_past_and_only_authored_materials_warn_of_metal() {
    let dir = temp_dir("bom");
    let uri = format!("data:application/octet-stream;base64,{}", encode_base64(&triangle_bytes()));
    let text = gltf(&uri, 1, 1, 0, "");
    let path = dir.join("bom.gltf");
    std::fs::write(&path, [b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat()).unwrap();
    let content = vrao_render::scene::gltf::load_content(&path, 0).expect("a glTF behind a byte-order mark loads");
    assert_eq!(content.meshes.len(), 1);
    // No material: the default one's metallicFactor of 1 is the spec's, not the file's.
    assert!(content.warnings.iter().all(|w| !w.contains("metallic")), "{:?}", content.warnings);
    let metal = text.replace(r#""materials": []"#, r#""materials": [{"pbrMetallicRoughness": {"metallicFactor": 1}}]"#);
    let metal =
        metal.replace(r#"{"attributes": {"POSITION": 0}}"#, r#"{"attributes": {"POSITION": 0}, "material": 0}"#);
    std::fs::write(&path, metal).unwrap();
    let content = vrao_render::scene::gltf::load_content(&path, 0).unwrap();
    assert!(content.warnings.iter().any(|w| w.contains("metallic-roughness")), "{:?}", content.warnings);
}
