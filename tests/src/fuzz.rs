//! Loader fuzzing on the stable toolchain: real files (the Cornell boxes'
//! OBJ and MTL, built-in scenes written as TOML, small EXRs) mutated by
//! seeded byte- and token-level edits, each run through the `vpl` command in
//! process, as a user would run it.
//!
//! An execution ends in one of three ways: the command accepts the input and
//! writes a finite image (exit 0), refuses it with one line (exit 2), or
//! breaks a promise: a panic, an exit 0 with a non-finite or missing image,
//! a refusal that is not one line, or an output left behind by a failed
//! command. The last kind is a *finding*; the fuzzer keeps its input.
//!
//! Every input is drawn from `stream(seed, 0, Purpose::TEST, execution)`, so
//! a run is reproducible from its seed and execution index. Inputs that
//! broke a promise once are kept in `tests/data/fuzz-regressions/<target>/`
//! and replayed by every test run.

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use vpl_core::glam::Vec3;
use vpl_core::{Image, Purpose, RngStream, SceneSetup, stream};
use vpl_scene_io::ImageFile;

/// What a fuzz target feeds the loaders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// A mutated OBJ beside its unmutated MTL, rendered.
    Obj,
    /// A mutated MTL beside its unmutated OBJ, rendered.
    Mtl,
    /// A mutated scene TOML (built-ins and an OBJ scene with lights,
    /// overrides and a sequence), rendered.
    Toml,
    /// A mutated EXR, read as a reference image.
    Exr,
    /// A mutated Mitsuba XML scene (Mitsuba's Cornell box as analytic
    /// shapes, and a scene with includes, parameters, spheres, a PLY mesh,
    /// layered BSDFs and point, spot and sun emitters), rendered.
    Mitsuba,
    /// A mutated PLY mesh (binary and ASCII) beside the Mitsuba scene that
    /// uses it, rendered.
    Ply,
    /// A mutated glTF (JSON) with its buffers and a texture, named by a
    /// scene TOML that lights it, rendered.
    Gltf,
    /// A mutated binary glTF (GLB: JSON and BIN chunks, an emissive
    /// triangle pair and a punctual light), rendered.
    Glb,
    /// A mutated scene TOML with a `[sequence]`, rendered as a sequence of
    /// three frames into a folder (`vpl sequence`).
    Sequence,
    /// A finished tiny Table 1 run whose `spec.json` or one unit file is
    /// mutated, merged (`vpl merge`).
    Table1,
}

impl Target {
    /// All targets.
    pub const ALL: [Target; 10] = [
        Target::Obj,
        Target::Mtl,
        Target::Toml,
        Target::Exr,
        Target::Mitsuba,
        Target::Ply,
        Target::Gltf,
        Target::Glb,
        Target::Sequence,
        Target::Table1,
    ];

    /// Its name (the folder of its regressions).
    pub fn name(self) -> &'static str {
        match self {
            Target::Obj => "obj",
            Target::Mtl => "mtl",
            Target::Toml => "toml",
            Target::Exr => "exr",
            Target::Mitsuba => "mitsuba",
            Target::Ply => "ply",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::Sequence => "sequence",
            Target::Table1 => "table1",
        }
    }

    /// The target named `name`.
    pub fn parse(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// How one execution ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0 with a finite image.
    Accepted,
    /// Exit 2 with one line.
    Refused(String),
    /// A broken promise, described.
    Finding(String),
}

/// The unmutated inputs of a target: (file name, bytes) pairs; the first is
/// the one mutated, the others are written beside it unchanged.
pub struct Seed {
    /// Files of the seed; `files[0]` is mutated.
    pub files: Vec<(String, Vec<u8>)>,
}

fn data(rel: &str) -> Vec<u8> {
    std::fs::read(crate::data_dir().join(rel)).unwrap_or_else(|e| panic!("fuzz seed {rel}: {e}"))
}

/// A small PLY tetrahedron, binary little-endian or ASCII.
fn ply_tetrahedron(binary: bool) -> Vec<u8> {
    let v = [[0.0f32, -1.0, 0.0], [0.5, -1.0, 0.0], [0.0, -1.0, 0.5], [0.1, -0.5, 0.1]];
    let f = [[0u32, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
    let fmt = if binary { "binary_little_endian" } else { "ascii" };
    let mut b = format!(
        "ply\nformat {fmt} 1.0\ncomment a tetrahedron\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for p in v {
        if binary {
            p.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
        } else {
            b.extend(format!("{} {} {}\n", p[0], p[1], p[2]).bytes());
        }
    }
    for t in f {
        if binary {
            b.push(3);
            t.iter().for_each(|i| b.extend_from_slice(&(*i as i32).to_le_bytes()));
        } else {
            b.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        }
    }
    b
}

/// A Mitsuba scene that uses most of what the reader supports.
const MITSUBA_SCENE: &str = r#"<scene version="3.0.0">
    <default name="res" value="16"/>
    <default name="radius" value="0.3"/>
    <include filename="bsdfs.xml"/>
    <sensor type="thinlens">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="diagonal"/>
        <float name="aperture_radius" value="0.01"/>
        <float name="focus_distance" value="3"/>
        <transform name="to_world"><scale x="-1"/><scale x="-1"/><lookat origin="0, 0, 3.5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><translate y="-1"/></transform><ref id="white"/></shape>
    <shape type="cube"><transform name="to_world"><matrix value="0.3 0 0 -0.4  0 0.3 0 -0.7  0 0 0.3 0  0 0 0 1"/></transform><ref id="plastic"/></shape>
    <shape type="sphere"><point name="center" x="0.4" y="-0.6" z="0.2"/><float name="radius" value="$radius"/><ref id="metal"/></shape>
    <shape type="disk"><transform name="to_world"><rotate x="1" angle="90"/><scale value="0.3"/><translate y="0.99"/></transform>
        <ref id="white"/><ref id="lamp"/></shape>
    <shape type="ply"><string name="filename" value="m.ply"/><boolean name="flip_normals" value="false"/><bsdf type="dielectric"/></shape>
    <emitter type="area" id="lamp"><spectrum name="radiance" value="400:2, 500:8, 600:9, 700:9"/></emitter>
    <emitter type="point"><point name="position" x="0" y="0.5" z="0.5"/><rgb name="intensity" value="0.5"/></emitter>
    <emitter type="spot"><transform name="to_world"><lookat origin="0, 0.9, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="2"/><float name="cutoff_angle" value="30"/></emitter>
    <emitter type="directional"><vector name="direction" x="0.2" y="-1" z="0.1"/><rgb name="irradiance" value="0.3"/></emitter>
</scene>
"#;

/// The BSDFs [`MITSUBA_SCENE`] includes.
const MITSUBA_BSDFS: &str = r#"<scene version="3.0.0">
    <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.6"/></bsdf></bsdf>
    <bsdf type="roughplastic" id="plastic"><rgb name="diffuse_reflectance" value="0.2 0.3 0.6"/><float name="alpha" value="0.05"/>
        <string name="int_ior" value="bk7"/></bsdf>
    <bsdf type="roughconductor" id="metal"><string name="material" value="Au"/><float name="alpha" value="0.02"/></bsdf>
</scene>
"#;

/// An OBJ scene with lights, a material override and a sequence.
const OBJ_SCENE: &str = "[geometry]\nobj = \"cbox.obj\"\nup = \"y\"\nscale = 1.0\n\n[camera]\norigin = [0, 0, 3.9]\ntarget = [0, 0, 0]\nfov = 39.3\n\
                             resolution = [8, 6]\n\n[[lights]]\ntype = \"point\"\nposition = [0, 0.5, 0]\nintensity = [1, 1, 1]\n\n[[lights]]\n\
                             type = \"spot\"\nposition = [0, 0.9, 0]\ndirection = [0, -1, 0]\nintensity = [2, 2, 2]\nangle = 40\n\n[[materials]]\n\
                             name = \"red\"\nalbedo = [0.6, 0.1, 0.1]\nkappa = 0.5\nspecular = [0.2, 0.2, 0.2]\n\n[sequence]\nfps = 2\nduration = 1\n\
                             camera = [ { t = 0, origin = [0, 0, 3.9], target = [0, 0, 0] } ]\nlights = [ { light = 0, t = 1, position = [0.2, 0.5, 0] } ]\n";

/// The seeds of `target`.
pub fn seeds(target: Target) -> Vec<Seed> {
    let cbox = ("cbox.obj".to_string(), data("cornell-box/cbox.obj"));
    let cbox_mtl = ("cbox.mtl".to_string(), data("cornell-box/cbox.mtl"));
    let orig = ("CornellBox-Original.obj".to_string(), data("mcguire/CornellBox-Original.obj"));
    let orig_mtl = ("CornellBox-Original.mtl".to_string(), data("mcguire/CornellBox-Original.mtl"));
    match target {
        Target::Obj => vec![Seed { files: vec![cbox, cbox_mtl] }, Seed { files: vec![orig, orig_mtl] }],
        Target::Mtl => vec![Seed { files: vec![cbox_mtl, cbox] }, Seed { files: vec![orig_mtl, orig] }],
        Target::Toml => {
            let mut v: Vec<Seed> = ["cornell", "courtyard", "corner"]
                .iter()
                .map(|b| Seed {
                    files: vec![(
                        "s.toml".into(),
                        vpl_scene_io::scene_toml(&SceneSetup::builtin(b).expect("built-in").description).into_bytes(),
                    )],
                })
                .collect();
            v.push(Seed { files: vec![("s.toml".into(), OBJ_SCENE.as_bytes().to_vec()), cbox, cbox_mtl] });
            v
        }
        Target::Exr => {
            let mut small = Image::new(4, 3);
            for (i, p) in small.data.iter_mut().enumerate() {
                *p = Vec3::new(i as f32 * 0.1, 0.5, 1.0 / (1.0 + i as f32));
            }
            let reference = Image::read_exr(crate::data_dir().join("cornell-box/reference_indirect.exr")).expect("reference EXR");
            let reference = vpl_render::metrics::downsample(&reference, 16).expect("256 is a multiple of 16");
            [small, reference].iter().map(|i| Seed { files: vec![("r.exr".into(), i.encode_exr().expect("encode"))] }).collect()
        }
        Target::Mitsuba => {
            let scene = ("s.xml".to_string(), MITSUBA_SCENE.as_bytes().to_vec());
            let bsdfs = ("bsdfs.xml".to_string(), MITSUBA_BSDFS.as_bytes().to_vec());
            let ply = ("m.ply".to_string(), ply_tetrahedron(true));
            vec![Seed { files: vec![("s.xml".into(), data("cornell-box/cornell.xml"))] }, Seed { files: vec![scene, bsdfs, ply] }]
        }
        Target::Ply => {
            let scene = ("s.xml".to_string(), MITSUBA_SCENE.as_bytes().to_vec());
            let bsdfs = ("bsdfs.xml".to_string(), MITSUBA_BSDFS.as_bytes().to_vec());
            [true, false]
                .iter()
                .map(|b| Seed { files: vec![("m.ply".into(), ply_tetrahedron(*b)), scene.clone(), bsdfs.clone()] })
                .collect()
        }
        Target::Gltf => {
            let gltf = |rel: &str| gltf_data(rel);
            let lit = |model: &str| {
                format!(
                    "[geometry]\ngltf = \"{model}\"\n[camera]\norigin = [1.5, 1.2, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 45.0\n\
                     resolution = [8, 6]\n[[lights]]\ntype = \"point\"\nposition = [0.8, 1.5, 0.6]\nintensity = [2.0, 2.0, 2.0]\n"
                )
                .into_bytes()
            };
            vec![
                Seed {
                    files: vec![
                        ("box.gltf".into(), gltf("Box/Box.gltf")),
                        ("s.toml".into(), lit("box.gltf")),
                        ("Box0.bin".into(), gltf("Box/Box0.bin")),
                    ],
                },
                Seed {
                    files: vec![
                        ("tex.gltf".into(), gltf("BoxTextured/BoxTextured-matching.gltf")),
                        ("s.toml".into(), lit("tex.gltf")),
                        ("BoxTextured0.bin".into(), gltf("BoxTextured/BoxTextured0.bin")),
                        ("CesiumLogoFlat.png".into(), gltf("BoxTextured/CesiumLogoFlat.png")),
                    ],
                },
            ]
        }
        Target::Glb => vec![Seed { files: vec![("s.glb".into(), glb_scene())] }],
        Target::Sequence => {
            let cbox = ("cbox.obj".to_string(), data("cornell-box/cbox.obj"));
            let cbox_mtl = ("cbox.mtl".to_string(), data("cornell-box/cbox.mtl"));
            let mut v: Vec<Seed> = ["courtyard", "corner"]
                .iter()
                .map(|b| Seed {
                    files: vec![(
                        "s.toml".into(),
                        vpl_scene_io::scene_toml(&SceneSetup::builtin(b).expect("built-in").description).into_bytes(),
                    )],
                })
                .collect();
            v.push(Seed { files: vec![("s.toml".into(), OBJ_SCENE.as_bytes().to_vec()), cbox, cbox_mtl] });
            v
        }
        Target::Table1 => table1_seeds(),
    }
}

/// A glTF sample of `vpl-core`'s test data.
fn gltf_data(rel: &str) -> Vec<u8> {
    let p = crate::data_dir().join("../../vpl-scene-io/tests/data/gltf").join(rel);
    std::fs::read(&p).unwrap_or_else(|e| panic!("fuzz seed {}: {e}", p.display()))
}

/// A small GLB: two triangles (a floor and an emissive quad's half) with
/// normals and u16 indices in the BIN chunk, a point light, a camera.
fn glb_scene() -> Vec<u8> {
    let mut bin = Vec::new();
    let positions = [[-1.0f32, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0], [-0.5, 1.0, -0.5], [0.5, 1.0, -0.5], [0.0, 1.0, 0.5]];
    for p in positions {
        p.iter().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    }
    for n in [[0.0f32, 1.0, 0.0]; 3].into_iter().chain([[0.0f32, -1.0, 0.0]; 3]) {
        n.iter().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    }
    for i in [0u16, 2, 1, 3, 4, 5] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_lights_punctual"],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":2.0,"color":[1,0.9,0.8]}}]}}}},
"buffers":[{{"byteLength":{len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":72}},{{"buffer":0,"byteOffset":72,"byteLength":72}},{{"buffer":0,"byteOffset":144,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[-1,0,-1],"max":[1,1,1]}},
{{"bufferView":1,"componentType":5126,"count":6,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.8,0.8,1]}},"emissiveFactor":[0.5,0.5,0.5]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"material":0}}]}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.9,"znear":0.01,"aspectRatio":1.333}}}}],
"nodes":[{{"mesh":0}},{{"extensions":{{"KHR_lights_punctual":{{"light":0}}}},"translation":[0,0.6,0]}},{{"camera":0,"translation":[0,0.5,3]}}],
"scenes":[{{"nodes":[0,1,2]}}],"scene":0}}"#,
        len = bin.len()
    );
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}

/// The tiny Table 1 run the `table1` target merges: maze, two frames, IR
/// and SMC, one seed. Made once a process (a few seconds).
fn table1_run() -> &'static Vec<(String, Vec<u8>)> {
    static RUN: std::sync::OnceLock<Vec<(String, Vec<u8>)>> = std::sync::OnceLock::new();
    RUN.get_or_init(|| {
        use vpl_bench::table1::{self, RowRun, Shard, Table1Spec};
        let spec = Table1Spec {
            profile: "fuzz".into(),
            rows: vec![RowRun { id: "maze".into(), start: 300, end: 302 }],
            methods: vec!["ir".into(), "smc".into()],
            size: (32, 24),
            truth_spp: 16,
            max_depth: 4,
            shadow_map_res: 16,
            seed: 1,
            seeds: 1,
            backend: vpl_bench::pipeline::BackendKind::Cpu,
        };
        let dir = std::env::temp_dir().join(format!("vpl-fuzz-table1-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        table1::run(&vpl_sampling::Registry::builtin(), &spec, &dir, Shard::ALL, &mut |_| {}).expect("the tiny Table 1 run");
        let mut files = Vec::new();
        collect(&dir, &dir, &mut files);
        let _ = std::fs::remove_dir_all(&dir);
        files.sort();
        files
    })
}

/// Every file under `dir`, named relative to `root`.
fn collect(root: &Path, dir: &Path, out: &mut Vec<(String, Vec<u8>)>) {
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(root, &p, out);
        } else if let (Ok(rel), Ok(bytes)) = (p.strip_prefix(root), std::fs::read(&p)) {
            out.push((rel.to_string_lossy().into_owned(), bytes));
        }
    }
}

/// One seed per file of the tiny run: that file mutated, the others beside it.
fn table1_seeds() -> Vec<Seed> {
    let files = table1_run();
    (0..files.len())
        .map(|k| {
            let mut f = vec![files[k].clone()];
            f.extend(files.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, x)| x.clone()));
            Seed { files: f }
        })
        .collect()
}

/// Tokens the mutator writes over numbers and names.
const VALUES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "NaN",
    "1e38",
    "3e38",
    "-3e38",
    "1e39",
    "0",
    "-0",
    "1e-45",
    "1e-30",
    "99999999999",
    "-1",
    "1e10",
    "1e20",
    "4294967295",
    "-2147483648",
    "18446744073709551616",
    "",
    "0x10",
    "1_0",
    "+",
    "-",
    ".",
    "e",
    "2e",
    "1.0.0",
];
/// Whole lines the mutator inserts, by target.
fn lines(target: Target) -> &'static [&'static str] {
    match target {
        Target::Obj => &[
            "mtllib /dev/zero",
            "mtllib cbox.obj",
            "mtllib missing.mtl",
            "mtllib cbox.mtl cbox.mtl",
            "usemtl nothere",
            "usemtl",
            "\u{feff}mtllib cbox.mtl",
            "f 1 2",
            "f 1",
            "f",
            "f -1 -2 -3",
            "f 0 0 0",
            "f 99999 1 2",
            "f 1/1/1 2/2/2 3/3/3",
            "f 1//99 2//1 3//1",
            "f -9999 -1 -2",
            "v 1e30 0 0",
            "v 0 4000 0",
            "v nan 0 0",
            "v 1 2",
            "vn 0 0 0",
            "vn nan 1 0",
            "vt 0.5",
            "o",
            "g x",
            "s off",
            "l 1 2",
            "p 1",
            "v 1 2 3 4 5 6 7",
        ],
        Target::Mtl => &[
            "Kd 0.8",
            "Ke 10 10",
            "Ke inf 1 1",
            "Ke 3e38",
            "Kd 1.5",
            "Ks 1 1",
            "Ka 1 1",
            "Tf 1",
            "Ns -5",
            "Ni 0",
            "d -halo",
            "d 2",
            "Tr 0.5",
            "illum 99",
            "illum -1",
            "newmtl",
            "newmtl light",
            "newmtl dup",
            "map_Kd",
            "map_Kd tex.png",
            "v 0 0 0",
            "Kd spectral a.rfl",
            "Kd xyz 1 1 1",
            "\u{feff}newmtl x",
        ],
        Target::Toml => &[
            "scale = 1e30",
            "scale = 0",
            "up = \"x\"",
            "up = \"z\"",
            "obj = \"/dev/zero\"",
            "obj = \"../cbox.obj\"",
            "gltf = \"/etc/passwd\"",
            "mitsuba = \"../../s.xml\"",
            "allow_outside = [\"/nonexistent\"]",
            "obj = \"cbox.mtl\"",
            "obj = \"missing.obj\"",
            "builtin = \"nothere\"",
            "emission = [3e38, 3e38, 3e38]",
            "albedo = [2, 2, 2]",
            "fov = 0",
            "fov = 179.9",
            "resolution = [0, 0]",
            "resolution = [100000, 100000]",
            "duration = 1e30",
            "fps = 1e-30",
            "fps = 1e9",
            "lens_radius = 1e30",
            "focus_distance = 0",
            "[[lights]]\ntype = \"point\"\nposition = [0, 1e30, 0]\nintensity = [1, 1, 1]",
            "[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = [1, 1, 1]",
            "[[lights]]\ntype = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, -1, 0]\nintensity = [1e38, 1, 1]\nangle = 1e-30",
            "[[materials]]\nname = \"nothere\"",
            "[[materials]]\nname = \"light\"\nemission = [1e12, 1e12, 1e12]",
            "[[materials]]\nname = \"floor\"\nior = 0\ntransmission = 2",
        ],
        Target::Mitsuba => &[
            "<include filename=\"s.xml\"/>",
            "<include filename=\"/dev/zero\"/>",
            "<include filename=\"../x.xml\"/>",
            "<include filename=\"/etc/passwd\"/>",
            "<include filename=\"bsdfs.xml\"/><include filename=\"bsdfs.xml\"/>",
            "<texture type=\"bitmap\" id=\"t2\"><string name=\"filename\" value=\"../../x.png\"/></texture>",
            "<shape type=\"cube\" a0=\"0\" a1=\"1\" a2=\"2\" a3=\"3\" a4=\"4\" a5=\"5\" a6=\"6\" a7=\"7\" a8=\"8\" a9=\"9\" b0=\"0\" b1=\"1\" b2=\"2\" b3=\"3\" b4=\"4\" b5=\"5\" b6=\"6\" b7=\"7\" b8=\"8\" b9=\"9\" c0=\"0\" c1=\"1\" c2=\"2\" c3=\"3\" c4=\"4\" c5=\"5\" c6=\"6\" c7=\"7\" c8=\"8\" c9=\"9\" d0=\"0\" d1=\"1\" d2=\"2\" d3=\"3\" d4=\"4\" d5=\"5\" d6=\"6\" d7=\"7\" d8=\"8\" d9=\"9\" e0=\"0\" e1=\"1\" e2=\"2\" e3=\"3\" e4=\"4\" e5=\"5\" e6=\"6\" e7=\"7\" e8=\"8\" e9=\"9\" f0=\"0\" f1=\"1\" f2=\"2\" f3=\"3\" f4=\"4\" f5=\"5\" f6=\"6\" f7=\"7\" f8=\"8\" f9=\"9\" g0=\"0\" g1=\"1\" g2=\"2\" g3=\"3\" g4=\"4\"/>",
            "<include filename=\"m.ply\"/>",
            "<default name=\"res\" value=\"$res\"/>",
            "<default name=\"res\" value=\"100000\"/>",
            "<shape type=\"sphere\"><float name=\"radius\" value=\"1e38\"/></shape>",
            "<shape type=\"sphere\"><float name=\"radius\" value=\"0\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>",
            "<shape type=\"obj\"><string name=\"filename\" value=\"/dev/zero\"/></shape>",
            "<shape type=\"ply\"><string name=\"filename\" value=\"s.xml\"/></shape>",
            "<shape type=\"cube\"><ref id=\"nope\"/></shape>",
            "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0\"/></transform></shape>",
            "<shape type=\"cube\"><transform name=\"to_world\"><matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 0\"/></transform></shape>",
            "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"3e38\"/></emitter></shape>",
            "<shape type=\"rectangle\"><emitter type=\"area\"><spectrum name=\"radiance\" value=\"500:1, 400:1\"/></emitter></shape>",
            "<bsdf type=\"twosided\" id=\"loop\"><ref id=\"loop\"/></bsdf>",
            "<bsdf type=\"dielectric\" id=\"white\"><float name=\"int_ior\" value=\"0\"/></bsdf>",
            "<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"-1\"/><rgb name=\"k\" value=\"nan\"/></bsdf>",
            "<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"s.xml\"/></texture>",
            "<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"0\"/></emitter>",
            "<emitter type=\"directional\"/>",
            "<emitter type=\"point\"><rgb name=\"intensity\" value=\"1e38\"/></emitter>",
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"180\"/></sensor>",
            "<sensor type=\"perspective\"><string name=\"focal_length\" value=\"0mm\"/></sensor>",
            "<!-- a comment -->",
            "<![CDATA[x]]>",
            "</scene>",
        ],
        Target::Ply => &[
            "element face 99999999",
            "element vertex 4000000000",
            "element junk 4000000000",
            "property list uchar uint vertex_indices",
            "property list uint uint vertex_indices",
            "format binary_big_endian 1.0",
            "end_header",
        ],
        Target::Gltf => &[
            "\"uri\": \"../secret.bin\",",
            "\"uri\": \"/dev/zero\",",
            "\"uri\": \"/etc/passwd\",",
            "\"uri\": \"%ff%fe.bin\",",
            "\"uri\": \"file:///etc/hostname\",",
            "\"uri\": \"https://example.com/x.bin\",",
            "\"uri\": \"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA\",",
            "\"uri\": \"data:application/octet-stream;base64,@@@\",",
            "\"byteStride\": 4,",
            "\"byteStride\": 0,",
            "\"byteOffset\": 4294967295,",
            "\"byteLength\": 18446744073709551615,",
            "\"componentType\": 5120,",
            "\"componentType\": 5121,",
            "\"componentType\": 5122,",
            "\"componentType\": 5126,",
            "\"type\": \"SCALAR\",",
            "\"type\": \"MAT4\",",
            "\"normalized\": true,",
            "\"count\": 0,",
            "\"count\": 5000000000,",
            "\"sparse\": {\"count\": 1, \"indices\": {\"bufferView\": 0, \"componentType\": 5123}, \"values\": {\"bufferView\": 0}},",
            "\"sparse\": {\"count\": 4000000000, \"indices\": {\"bufferView\": 0, \"componentType\": 5125}, \"values\": {\"bufferView\": 0}},",
            "\"children\": [0, 0],",
            "\"children\": [1, 1],",
            "\"mode\": 0,",
            "\"mode\": 5,",
            "\"mode\": 6,",
            "\"bufferView\": 99,",
            "\"mimeType\": \"image/png\",",
            "\"mimeType\": \"image/ktx2\",",
            "\"extensionsRequired\": [\"KHR_draco_mesh_compression\"],",
            "\"extensions\": {\"KHR_materials_emissive_strength\": {\"emissiveStrength\": 1e30}},",
            "\"extensions\": {\"KHR_node_visibility\": {\"visible\": false}},",
            "\"scale\": [1e30, 1e30, 1e30],",
            "\"matrix\": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0],",
            "\"rotation\": [0, 0, 0, 0],",
            "\"emissiveFactor\": [1e38, 1, 1],",
            "\"baseColorFactor\": [2, 2, 2, 1],",
            "\"min\": [0, 0, 0], \"max\": [0, 0, 0],",
        ],
        Target::Sequence => &[
            "fps = inf",
            "fps = 1e-30",
            "fps = 1e9",
            "duration = 1e30",
            "duration = 0",
            "duration = -1",
            "camera = [ { t = nan, origin = [0, 0, 3.9], target = [0, 0, 0] } ]",
            "camera = [ { t = 0, origin = [0, 0, 3.9], target = [0, 0, 3.9] } ]",
            "camera = [ { t = 1e30, origin = [1e30, 0, 0], target = [0, 0, 0] } ]",
            "lights = [ { light = 99, t = 0, position = [0, 0, 0] } ]",
            "lights = [ { light = 0, t = 0, direction = [0, 0, 0] } ]",
            "lights = [ { light = 0, t = 0.5, position = [0, 1e30, 0] } ]",
            "[sequence]\nfps = 30\nduration = 1e6",
            "[sequence]",
            "lens_radius = 1e20",
        ],
        Target::Table1 => &[
            "\"seeds\": 1000,",
            "\"seeds\": 0,",
            "\"methods\": [\"ir\", \"ir\"],",
            "\"methods\": [],",
            "\"rows\": [],",
            "\"size\": [0, 0],",
            "\"size\": [100000, 100000],",
            "\"truth_spp\": 0,",
            "\"frames\": [],",
            "\"seconds\": 1e309,",
            "\"samples\": 18446744073709551616,",
            "1e39,",
            "-1e39,",
            "[1e39, 0, 0],",
            "\"row\": \"../../etc\",",
            "\"row\": \"sponza\",",
            "\"method\": \"nope\",",
            "\"hash\": \"0\",",
        ],
        Target::Exr | Target::Glb => &[],
    }
}

fn pick<'a, T>(rng: &mut RngStream, items: &'a [T]) -> &'a T {
    &items[rng.below(items.len() as u32) as usize]
}

/// Byte ranges of the number-like tokens of `text`.
fn tokens(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() || bytes[i] == b'-' || bytes[i] == b'.' {
            let s = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || matches!(bytes[i], b'-' | b'.' | b'+')) {
                i += 1;
            }
            out.push((s, i));
        }
        i += 1;
    }
    out
}

/// The largest input the mutator makes (bytes).
pub const MAX_INPUT: usize = 1 << 18;

/// One to four seeded edits of `input`.
pub fn mutate(input: &[u8], target: Target, rng: &mut RngStream) -> Vec<u8> {
    let mut b = input.to_vec();
    let edits = 1 + rng.below(4);
    for _ in 0..edits {
        let textual = !matches!(target, Target::Exr | Target::Glb);
        match rng.below(if textual { 10 } else { 6 }) {
            // Flip a bit.
            0 if !b.is_empty() => {
                let i = rng.below(b.len() as u32) as usize;
                b[i] ^= 1 << rng.below(8);
            }
            // Overwrite a byte with an interesting one.
            1 if !b.is_empty() => {
                let i = rng.below(b.len() as u32) as usize;
                b[i] = *pick(rng, &[0u8, 0xff, 0x7f, 0x80, b'\n', b' ', b'#', b'/', b'-', b'9', b'"', b'[', b'=']);
            }
            // Truncate.
            2 if !b.is_empty() => {
                let i = rng.below(b.len() as u32) as usize;
                b.truncate(i);
            }
            // Overwrite a little-endian u32 / f32 (headers, sizes, pixels).
            3 if b.len() >= 4 => {
                let i = rng.below(b.len() as u32 - 3) as usize;
                let v: u32 = *pick(
                    rng,
                    &[0, 1, u32::MAX, 0x7fff_ffff, 0x8000_0000, 1_000_000_000, f32::NAN.to_bits(), f32::INFINITY.to_bits(), 65536],
                );
                b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            // Delete or duplicate a range.
            4 if !b.is_empty() => {
                let i = rng.below(b.len() as u32) as usize;
                let n = (1 + rng.below(64) as usize).min(b.len() - i);
                if rng.below(2) == 0 {
                    b.drain(i..i + n);
                } else {
                    let chunk = b[i..i + n].to_vec();
                    b.splice(i..i, chunk);
                }
            }
            // Random bytes.
            5 => {
                let i = rng.below(b.len() as u32 + 1) as usize;
                let n = 1 + rng.below(16) as usize;
                let junk: Vec<u8> = (0..n).map(|_| rng.below(256) as u8).collect();
                b.splice(i..i, junk);
            }
            // Replace a number.
            6 => {
                let t = tokens(&b);
                if !t.is_empty() {
                    let (s, e) = *pick(rng, &t);
                    b.splice(s..e, pick(rng, VALUES).bytes());
                }
            }
            // Insert a line from the dictionary.
            7 => {
                let l = lines(target);
                if !l.is_empty() {
                    let starts: Vec<usize> =
                        std::iter::once(0).chain(b.iter().enumerate().filter(|(_, c)| **c == b'\n').map(|(i, _)| i + 1)).collect();
                    let at = *pick(rng, &starts);
                    let line = format!("{}\n", pick(rng, l));
                    b.splice(at..at, line.bytes());
                }
            }
            // Delete, duplicate or swap lines.
            8 | 9 => {
                let text = String::from_utf8_lossy(&b).into_owned();
                let mut ls: Vec<&str> = text.split('\n').collect();
                if ls.len() >= 2 {
                    let i = rng.below(ls.len() as u32) as usize;
                    let j = rng.below(ls.len() as u32) as usize;
                    match rng.below(3) {
                        0 => {
                            ls.remove(i);
                        }
                        1 => ls.insert(j, ls[i]),
                        _ => ls.swap(i, j),
                    }
                    b = ls.join("\n").into_bytes();
                }
            }
            _ => {}
        }
    }
    b.truncate(MAX_INPUT);
    b
}

/// The `vpl` arguments of the `variant`-th way of rendering a fuzzed scene:
/// the path tracer, IR VPLs with ray-traced and with shadow-map visibility,
/// and the progressive renderer, all at 8×6.
fn command(scene: &Path, out: &Path, variant: u64) -> Vec<String> {
    let mut a: Vec<String> = ["vpl", "render", "--scene"].map(String::from).to_vec();
    a.push(scene.display().to_string());
    let rest: &[&str] = match variant % 4 {
        0 => &["--method", "path", "--spp", "2", "--max-depth", "4"],
        1 => &[
            "--method",
            "vpl",
            "--sampler",
            "ir",
            "--vpls",
            "16",
            "--visibility",
            "raytrace",
            "--shading",
            "exhaustive",
            "--direct-samples",
            "2",
        ],
        2 => &["--method", "vpl", "--sampler", "ir", "--vpls", "16", "--shadowmap-res", "16", "--direct-samples", "2"],
        _ => &["--method", "progressive", "--passes", "1", "--vpl-paths", "4", "--caustic-paths", "64"],
    };
    a.extend(rest.iter().map(|s| s.to_string()));
    a.extend(["--size", "8x6", "--threads", "1", "--quiet", "--out"].map(String::from));
    a.push(out.display().to_string());
    a
}

static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);
/// Executions under way in this process (a panic hook cannot tell a worker
/// thread of a target from a test's own thread).
static RUNNING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Keeps the message of a panic inside a fuzz execution for [`run_one`]
/// instead of printing it (a fuzz run would print thousands); panics outside
/// executions (a failing assertion of a test) print as usual.
pub fn quiet_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if RUNNING.load(std::sync::atomic::Ordering::SeqCst) == 0 {
                return previous(info);
            }
            let at = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{msg}{at}"));
        }));
    });
}

/// Runs `input` (the mutated `seed.files[0]`) through `target` in the empty
/// folder `dir`; `variant` picks the renderer. The folder is emptied after.
pub fn run_one(target: Target, seed: &Seed, input: &[u8], dir: &Path, variant: u64) -> Outcome {
    RUNNING.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let caught = std::panic::catch_unwind(AssertUnwindSafe(|| execute(target, seed, input, dir, variant)));
    RUNNING.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
    let outcome = caught.unwrap_or_else(|_| {
        Outcome::Finding(format!("panic: {}", LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()).take().unwrap_or_default()))
    });
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.path().is_dir() {
                let _ = std::fs::remove_dir_all(e.path());
            } else {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    outcome
}

fn execute(target: Target, seed: &Seed, input: &[u8], dir: &Path, variant: u64) -> Outcome {
    if target == Target::Exr {
        return match Image::decode_exr(input, Path::new("r.exr")) {
            Ok(img) if img.data.iter().all(|p| p.is_finite()) => Outcome::Accepted,
            Ok(_) => Outcome::Finding("an EXR with a non-finite pixel was accepted".into()),
            Err(e) => Outcome::Refused(e.to_string()),
        };
    }
    for (i, (name, bytes)) in seed.files.iter().enumerate() {
        let bytes = if i == 0 { input } else { bytes };
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            let _ = std::fs::create_dir_all(parent);
        }
        if let Err(e) = std::fs::write(&path, bytes) {
            return Outcome::Finding(format!("cannot write the input: {e}"));
        }
    }
    let before: Vec<PathBuf> = listing(dir);
    match target {
        Target::Sequence => return execute_sequence(dir, variant, &before),
        Target::Table1 => return execute_merge(dir, &before),
        _ => {}
    }
    let scene = dir.join(match target {
        Target::Mtl | Target::Ply | Target::Gltf => &seed.files[1].0,
        _ => &seed.files[0].0,
    });
    let out = dir.join("out.exr");
    let code = vpl_cli::run(&vpl_sampling::Registry::builtin(), command(&scene, &out, variant));
    match code {
        0 => match Image::read_exr(&out) {
            Ok(img) if img.data.iter().all(|p| p.is_finite()) => {
                if dir.join("out.png").is_file() {
                    Outcome::Accepted
                } else {
                    Outcome::Finding("exit 0 without the PNG preview".into())
                }
            }
            Ok(_) => Outcome::Finding("exit 0 with a non-finite pixel".into()),
            Err(e) => Outcome::Finding(format!("exit 0 but the output does not read back: {e}")),
        },
        2 => refused_cleanly(dir, &before),
        c => Outcome::Finding(format!("exit code {c}")),
    }
}

/// Exit 2: nothing may be left beside the inputs.
fn refused_cleanly(dir: &Path, before: &[PathBuf]) -> Outcome {
    let left: Vec<PathBuf> = listing(dir).into_iter().filter(|p| !before.contains(p)).collect();
    if left.is_empty() { Outcome::Refused("exit 2".into()) } else { Outcome::Finding(format!("exit 2 left {left:?} behind")) }
}

/// `vpl sequence` of three frames (IR or SMC) into `dir/seq`: on success
/// every frame's EXR is finite and the CSV is there.
fn execute_sequence(dir: &Path, variant: u64, before: &[PathBuf]) -> Outcome {
    let out = dir.join("seq");
    let sampler = if variant.is_multiple_of(2) { "ir" } else { "smc" };
    let args: Vec<String> = [
        "vpl",
        "sequence",
        "--scene",
        "s.toml",
        "--sampler",
        sampler,
        "--vpls",
        "16",
        "--size",
        "8x6",
        "--frames",
        "0..2",
        "--threads",
        "1",
        "--quiet",
        "--out",
    ]
    .iter()
    .map(|a| a.to_string())
    .chain([out.display().to_string()])
    .map(|a| if a == "s.toml" { dir.join("s.toml").display().to_string() } else { a })
    .collect();
    match vpl_cli::run(&vpl_sampling::Registry::builtin(), args) {
        0 => {
            let exrs: Vec<PathBuf> = listing(&out).into_iter().filter(|p| p.extension().is_some_and(|e| e == "exr")).collect();
            if exrs.len() != 2 {
                return Outcome::Finding(format!("exit 0 with {} frames of 2", exrs.len()));
            }
            for f in exrs {
                match Image::read_exr(&f) {
                    Ok(img) if img.data.iter().all(|p| p.is_finite()) => {}
                    Ok(_) => return Outcome::Finding(format!("exit 0 with a non-finite pixel in {}", f.display())),
                    Err(e) => return Outcome::Finding(format!("exit 0 but {} does not read back: {e}", f.display())),
                }
            }
            Outcome::Accepted
        }
        2 => refused_cleanly(dir, before),
        c => Outcome::Finding(format!("exit code {c}")),
    }
}

/// `vpl merge` of the run in `dir`: on success the table is there and
/// prints no infinity or NaN; on a refusal no output is left.
fn execute_merge(dir: &Path, before: &[PathBuf]) -> Outcome {
    let args = vec!["vpl".to_string(), "merge".into(), dir.display().to_string()];
    match vpl_cli::run(&vpl_sampling::Registry::builtin(), args) {
        0 => match std::fs::read_to_string(dir.join("table1.md")) {
            Ok(md) if md.contains("inf") || md.contains("NaN") => Outcome::Finding("exit 0 with inf or NaN in table1.md".into()),
            Ok(_) => Outcome::Accepted,
            Err(e) => Outcome::Finding(format!("exit 0 without table1.md: {e}")),
        },
        2 => refused_cleanly(dir, before),
        c => Outcome::Finding(format!("exit code {c}")),
    }
}

fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).map(|r| r.flatten().map(|e| e.path()).collect()).unwrap_or_default();
    v.sort();
    v
}

/// Counts of a fuzz run.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Executions.
    pub executions: u64,
    /// Inputs accepted (exit 0, finite image).
    pub accepted: u64,
    /// Inputs refused with one line.
    pub refused: u64,
    /// Broken promises.
    pub findings: Vec<Finding>,
}

/// An input that broke a promise.
#[derive(Clone, Debug)]
pub struct Finding {
    /// Execution index (with the run's seed, it redraws the input).
    pub execution: u64,
    /// Index of the seed it mutated (see [`seeds`]).
    pub seed: usize,
    /// What went wrong.
    pub what: String,
    /// The input.
    pub input: Vec<u8>,
}

/// The input of execution `i` of a run of `target` with `seed`: the index of
/// the seed it mutates and the mutated bytes.
pub fn input(target: Target, seeds: &[Seed], seed: u64, i: u64) -> (usize, Vec<u8>) {
    let mut rng = stream(seed, target as u64, Purpose::TEST, i);
    let k = rng.below(seeds.len() as u32) as usize;
    (k, mutate(&seeds[k].files[0].1, target, &mut rng))
}

/// Runs executions `first..` of `target` with `seed` until `stop(done)` says
/// so, in the scratch folder `dir`.
pub fn run(target: Target, seed: u64, first: u64, dir: &Path, mut stop: impl FnMut(u64) -> bool) -> Report {
    let seeds = seeds(target);
    let mut report = Report::default();
    std::fs::create_dir_all(dir).expect("fuzz scratch folder");
    let mut i = first;
    while !stop(report.executions) {
        let (k, input) = input(target, &seeds, seed, i);
        match run_one(target, &seeds[k], &input, dir, i) {
            Outcome::Accepted => report.accepted += 1,
            Outcome::Refused(_) => report.refused += 1,
            Outcome::Finding(what) => report.findings.push(Finding { execution: i, seed: k, what, input }),
        }
        report.executions += 1;
        i += 1;
    }
    report
}

/// The regression inputs of `target`: `tests/data/fuzz-regressions/<target>/*`,
/// each named `<seed index>-<anything>` (the seed whose other files go beside it).
pub fn regressions(target: Target) -> Vec<(PathBuf, usize, Vec<u8>)> {
    let dir = crate::data_dir().join("fuzz-regressions").join(target.name());
    let mut v: Vec<(PathBuf, usize, Vec<u8>)> = std::fs::read_dir(&dir)
        .map(|r| {
            r.flatten()
                .filter_map(|e| {
                    let p = e.path();
                    let name = p.file_name()?.to_string_lossy().into_owned();
                    let seed: usize = name.split('-').next()?.parse().ok()?;
                    let bytes = std::fs::read(&p).ok()?;
                    Some((p, seed, bytes))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}
