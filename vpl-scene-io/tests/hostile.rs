//! Scene files written to break the loaders (the second round of
//! `docs/robustness.md`): each class of glTF, Mitsuba and sandbox attack
//! must end in one error line, promptly, with no panic, no unbounded
//! allocation and no read outside the scene's folder.
#![cfg(all(feature = "mitsuba", feature = "gltf", feature = "toml", feature = "exr"))]

use std::path::Path;
use vpl_scene_io::LoadOptions;
use vpl_scene_io::SceneIoError;
use vpl_scene_io::gltf::{load_gltf, load_gltf_in};
use vpl_scene_io::mitsuba::load_mitsuba;
use vpl_scene_io::sandbox::Sandbox;

/// Three FLOAT VEC3 positions of one triangle, then three u16 indices.
fn triangle_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in p {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

/// A glTF with one triangle primitive over buffer `uri` (42 bytes), whose
/// accessors are `accessors` (JSON), POSITION accessor 0 and indices 1
/// unless `primitive` says otherwise.
fn gltf(uri: &str, views: &str, accessors: &str, primitive: &str, extra: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":42,"uri":"{uri}"}}],
        "bufferViews":[{views}],"accessors":[{accessors}],
        "meshes":[{{"primitives":[{primitive}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}]{extra}}}"#
    )
}

const VIEWS: &str = r#"{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}"#;
const POSITIONS: &str = r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#;
const INDICES: &str = r#"{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}"#;
const PRIMITIVE: &str = r#"{"attributes":{"POSITION":0},"indices":1}"#;

/// Writes `text` as `name` with the triangle's buffer beside it, loads it,
/// and returns the error line (the load must fail).
fn refused(dir: &Path, name: &str, text: &str) -> String {
    std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    let e = load_gltf(&p, None).expect_err(name).to_string();
    assert!(!e.contains('\n'), "{name}: one line: {e}");
    e
}

#[test]
fn the_well_formed_triangle_loads() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.bin"), triangle_bin()).unwrap();
    let p = dir.path().join("ok.gltf");
    std::fs::write(&p, gltf("tri.bin", VIEWS, &format!("{POSITIONS},{INDICES}"), PRIMITIVE, "")).unwrap();
    let d = load_gltf(&p, None).unwrap();
    assert_eq!(d.mesh.triangles.len(), 1);
    // A %-escaped name that decodes to UTF-8 is read.
    std::fs::write(dir.path().join("tri a.bin"), triangle_bin()).unwrap();
    std::fs::write(&p, gltf("tri%20a.bin", VIEWS, &format!("{POSITIONS},{INDICES}"), PRIMITIVE, "")).unwrap();
    assert_eq!(load_gltf(&p, None).unwrap().mesh.triangles.len(), 1);
}

/// Accessors of a type their use forbids, strides under the element size
/// and views past their buffer: each panicked inside the `gltf` reader.
#[test]
fn accessors_the_reader_would_misread_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let all = |positions: &str, indices: &str| format!("{positions},{indices}");
    let cases = [
        // POSITION of bytes with a stride of 4 (under 12).
        (
            gltf(
                "tri.bin",
                r#"{"buffer":0,"byteOffset":0,"byteLength":36,"byteStride":4},{"buffer":0,"byteOffset":36,"byteLength":6}"#,
                &all(r#"{"bufferView":0,"componentType":5121,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}"#, INDICES),
                PRIMITIVE,
                "",
            ),
            "POSITION must be FLOAT VEC3",
        ),
        // Index accessors of FLOAT, BYTE and SHORT.
        (
            gltf("tri.bin", VIEWS, &all(POSITIONS, r#"{"bufferView":1,"componentType":5126,"count":1,"type":"SCALAR"}"#), PRIMITIVE, ""),
            "indices must be",
        ),
        (
            gltf("tri.bin", VIEWS, &all(POSITIONS, r#"{"bufferView":1,"componentType":5120,"count":3,"type":"SCALAR"}"#), PRIMITIVE, ""),
            "indices must be",
        ),
        (
            gltf("tri.bin", VIEWS, &all(POSITIONS, r#"{"bufferView":1,"componentType":5122,"count":3,"type":"SCALAR"}"#), PRIMITIVE, ""),
            "indices must be",
        ),
        // A NORMAL of shorts.
        (
            gltf(
                "tri.bin",
                VIEWS,
                &all(POSITIONS, r#"{"bufferView":0,"componentType":5122,"count":3,"type":"VEC3","normalized":true}"#),
                r#"{"attributes":{"POSITION":0,"NORMAL":1}}"#,
                "",
            ),
            "NORMAL must be FLOAT VEC3",
        ),
        // A view that reaches past its buffer.
        (
            gltf(
                "tri.bin",
                r#"{"buffer":0,"byteOffset":40,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}"#,
                &all(POSITIONS, INDICES),
                PRIMITIVE,
                "",
            ),
            "reaches past buffer 0",
        ),
        // More elements than the view holds.
        (
            gltf("tri.bin", VIEWS, &all(POSITIONS, r#"{"bufferView":1,"componentType":5123,"count":300,"type":"SCALAR"}"#), PRIMITIVE, ""),
            "reach past buffer view 1",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let e = refused(dir.path(), &format!("case{i}.gltf"), text);
        assert!(e.contains(want), "case {i}: {e}");
    }
}

/// A sparse accessor asks for as many elements as it likes with a few
/// bytes: the mesh it would make is weighed against the memory limit before
/// anything is allocated.
#[test]
fn sparse_accessors_are_weighed_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    // 5·10⁹ zero vertices with one sparse entry: 60 GB asked by a small file.
    let sparse = r#"{"componentType":5126,"count":5000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,1],"sparse":{"count":1,
        "indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}}}"#;
    let e = refused(dir.path(), "huge.gltf", &gltf("tri.bin", VIEWS, sparse, r#"{"attributes":{"POSITION":0}}"#, ""));
    assert!(e.contains("more than the") && e.contains("memory limit"), "{e}");
    // A sparse count above the accessor's.
    let over = r#"{"componentType":5126,"count":1,"type":"VEC3","min":[0,0,0],"max":[1,1,1],"sparse":{"count":3,
        "indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}}}"#;
    let e = refused(dir.path(), "over.gltf", &gltf("tri.bin", VIEWS, over, r#"{"attributes":{"POSITION":0}}"#, ""));
    assert!(e.contains("3 sparse elements for 1"), "{e}");
    // Under a memory limit, a dense mesh over it is refused too.
    std::fs::write(dir.path().join("tri.bin"), triangle_bin()).unwrap();
    let p = dir.path().join("ok.gltf");
    std::fs::write(&p, gltf("tri.bin", VIEWS, &format!("{POSITIONS},{INDICES}"), PRIMITIVE, "")).unwrap();
    let tight = Sandbox::for_scene(&p, &LoadOptions { memory_limit: Some(64), ..Default::default() }).unwrap();
    let e = load_gltf_in(&p, None, &tight).unwrap_err().to_string();
    assert!(e.contains("memory limit"), "{e}");
}

/// URIs: %-escapes that are not UTF-8, schemes other than file and data,
/// and paths that leave the scene's folder (relative, absolute, `file:`,
/// a device) are refused naming the reference; an accessor whose data
/// disagrees with its min and max is refused without quoting the data.
#[test]
fn uris_stay_in_the_folder_and_errors_quote_no_contents() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene");
    std::fs::create_dir(&scene).unwrap();
    std::fs::write(dir.path().join("secret.bin"), triangle_bin()).unwrap();
    let secret = dir.path().join("secret.bin");
    let with = |uri: &str| gltf(uri, VIEWS, &format!("{POSITIONS},{INDICES}"), PRIMITIVE, "");
    let e = refused(&scene, "escape.gltf", &with("%ff%fe.bin"));
    assert!(e.contains("%-escapes do not decode to UTF-8"), "{e}");
    let e = refused(&scene, "http.gltf", &with("https://example.com/tri.bin"));
    assert!(e.contains("only relative paths"), "{e}");
    for uri in ["../secret.bin".to_string(), secret.display().to_string(), format!("file://{}", secret.display()), "/dev/zero".into()] {
        let e = refused(&scene, "outside.gltf", &with(&uri));
        assert!(e.contains("leaves the scene's folder") && e.contains("--allow-outside"), "{uri}: {e}");
    }
    // Allowed, the outside buffer is read; a device is still refused as one.
    let p = scene.join("outside.gltf");
    std::fs::write(&p, with("../secret.bin")).unwrap();
    assert!(load_gltf_in(&p, None, &Sandbox::for_scene(&p, &LoadOptions::allowing(dir.path())).unwrap()).is_ok());
    std::fs::write(&p, with("/dev/zero")).unwrap();
    let e = load_gltf_in(&p, None, &Sandbox::for_scene(&p, &LoadOptions::allowing("/dev")).unwrap()).unwrap_err().to_string();
    assert!(e.contains("a device"), "{e}");
    // Positions of 1234.5 under a max of 1: named by index, never by value.
    let mut bin = triangle_bin();
    bin[..4].copy_from_slice(&1234.5f32.to_le_bytes());
    std::fs::write(scene.join("bad.bin"), &bin).unwrap();
    std::fs::write(&p, with("bad.bin")).unwrap();
    let e = load_gltf(&p, None).unwrap_err().to_string();
    assert!(e.contains("POSITION 0 of accessor 0") && !e.contains("1234"), "{e}");
}

/// An image whose bufferView lies past its buffer (a panic in the `gltf`
/// importer) and one that names a file outside the folder.
#[test]
fn images_are_read_through_the_same_checks() {
    let dir = tempfile::tempdir().unwrap();
    let textured = |image: &str, views: &str| {
        gltf(
            "tri.bin",
            views,
            &format!("{POSITIONS},{INDICES}"),
            r#"{"attributes":{"POSITION":0},"indices":1,"material":0}"#,
            &format!(
                r#","materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],"textures":[{{"source":0}}],"images":[{image}]"#
            ),
        )
    };
    let views = format!(r#"{VIEWS},{{"buffer":0,"byteOffset":30,"byteLength":4000}}"#);
    let e = refused(dir.path(), "view.gltf", &textured(r#"{"bufferView":2,"mimeType":"image/png"}"#, &views));
    assert!(e.contains("buffer view 2") && e.contains("reaches past buffer 0"), "{e}");
    let e = refused(dir.path(), "uri.gltf", &textured(r#"{"uri":"/etc/passwd"}"#, VIEWS));
    assert!(e.contains("'/etc/passwd' leaves the scene's folder"), "{e}");
    // Bytes that are no image: named as such, not quoted.
    std::fs::write(dir.path().join("fake.png"), b"root:x:0:0:root:/root:/bin/bash\n").unwrap();
    let e = refused(dir.path(), "fake.gltf", &textured(r#"{"uri":"fake.png"}"#, VIEWS));
    assert!(e.contains("neither PNG nor JPEG") && !e.contains("root:"), "{e}");
}

/// Mitsuba files that include the next file twice, 40 deep, would expand
/// 2⁴⁰ includes; elements with thousands of attributes take the XML parser
/// quadratic time; includes and meshes outside the folder are refused.
#[test]
fn mitsuba_includes_and_attributes_are_bounded_and_stay_in_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    for i in 0..40 {
        let next = format!("<include filename=\"f{}.xml\"/>", i + 1);
        std::fs::write(dir.path().join(format!("f{i}.xml")), format!("<scene version=\"3.0.0\">{next}{next}</scene>")).unwrap();
    }
    std::fs::write(dir.path().join("f40.xml"), "<scene version=\"3.0.0\"/>").unwrap();
    let t = std::time::Instant::now();
    let e = load_mitsuba(&dir.path().join("f0.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("more than 4096 <include>s"), "{e}");
    assert!(t.elapsed().as_secs() < 30, "took {:?}", t.elapsed());
    let attrs: String = (0..200_000).map(|i| format!(" a{i}=\"1\"")).collect();
    std::fs::write(dir.path().join("attrs.xml"), format!("<scene version=\"3.0.0\">\n<shape type=\"cube\"{attrs}/></scene>")).unwrap();
    let t = std::time::Instant::now();
    let e = load_mitsuba(&dir.path().join("attrs.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("attrs.xml:2:") && e.contains("at most 64 are read"), "{e}");
    assert!(t.elapsed().as_secs() < 30, "took {:?}", t.elapsed());
    for (body, reference) in [
        ("<include filename=\"/etc/passwd\"/>", "/etc/passwd"),
        ("<include filename=\"../x.xml\"/>", "../x.xml"),
        ("<shape type=\"ply\"><string name=\"filename\" value=\"/etc/passwd\"/></shape>", "/etc/passwd"),
        (
            "<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" value=\"/etc/hostname\"/></texture></bsdf>\
             <shape type=\"cube\"><ref id=\"x\"/></shape>",
            "/etc/hostname",
        ),
    ] {
        let body = body.replace("<bsdf type", "<bsdf id=\"x\" type");
        std::fs::write(dir.path().join("s.xml"), format!("<scene version=\"3.0.0\">{body}</scene>")).unwrap();
        let e = load_mitsuba(&dir.path().join("s.xml"), &[]).unwrap_err().to_string();
        assert!(e.contains(&format!("'{reference}' leaves the scene's folder")), "{body}: {e}");
    }
}

/// A mesh file named by many shapes is read and expanded for each: the
/// files of all shapes together are weighed against the memory limit.
#[test]
fn mitsuba_meshes_named_many_times_are_weighed_together() {
    let dir = tempfile::tempdir().unwrap();
    let mut obj = String::new();
    for i in 0..2000 {
        obj.push_str(&format!("v {i} 0 0\nv {i} 1 0\nv {i} 0 1\n"));
    }
    obj.push_str("f 1 2 3\n");
    std::fs::write(dir.path().join("m.obj"), &obj).unwrap();
    let shape = "<shape type=\"obj\"><string name=\"filename\" value=\"m.obj\"/></shape>";
    let light = "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"1\" z=\"0\"/><rgb name=\"intensity\" value=\"1\"/></emitter>";
    let scene = |n: usize| format!("<scene version=\"3.0.0\">{light}{}</scene>", shape.repeat(n));
    let p = dir.path().join("s.xml");
    let limited = |n: usize| {
        std::fs::write(&p, scene(n)).unwrap();
        let options = LoadOptions { memory_limit: Some(20 * obj.len() as u64), ..Default::default() };
        vpl_scene_io::load_with(p.to_str().unwrap(), &options)
    };
    assert!(limited(20).is_ok());
    let e = limited(21).unwrap_err().to_string();
    assert!(e.contains("s.xml:1:") && e.contains("mesh files come to more than"), "{e}");
}

/// A TOML scene's model, and a bare model given on the command line: the
/// file the user names may lie anywhere; what it names may not.
#[test]
fn a_scene_file_names_only_files_in_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("inner");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(dir.path().join("tri.bin"), triangle_bin()).unwrap();
    let model = dir.path().join("m.gltf");
    let emissive = r#"{"attributes":{"POSITION":0},"indices":1,"material":0}"#;
    let lamp = r#","materials":[{"emissiveFactor":[1,1,1]}]"#;
    std::fs::write(&model, gltf("tri.bin", VIEWS, &format!("{POSITIONS},{INDICES}"), emissive, lamp)).unwrap();
    let toml = inner.join("s.toml");
    std::fs::write(&toml, "[geometry]\ngltf = \"../m.gltf\"\n[[lights]]\ntype = \"point\"\nposition = [0, 0, 1]\nintensity = [1, 1, 1]\n")
        .unwrap();
    let e = vpl_scene_io::load(toml.to_str().unwrap()).unwrap_err();
    assert!(matches!(e, SceneIoError::OutsideScene { .. }), "{e}");
    assert!(vpl_scene_io::load_with(toml.to_str().unwrap(), &LoadOptions::allowing(dir.path())).is_ok());
    // The model named directly loads from wherever it is.
    let setup = vpl_scene_io::load(model.to_str().unwrap());
    assert!(setup.is_ok(), "{:?}", setup.err());
}
