//! `--backend gpu` against `--backend cpu`: the same frames of a sequence
//! through the whole pipeline (sampler with SMC's rays on the GPU, G-buffer,
//! visibility, shading).
//!
//! The GPU stages round differently from the CPU's (see the vpl-gpu kernel
//! tests), and the samplers read the G-buffer, so a rounding difference can
//! in principle change a sampler's decision and then the VPLs. Tolerance:
//! per frame, Σ|gpu − cpu|² / Σ|cpu|² ≤ 1e-6 (the shading twins agree to
//! ~1e-14 on lavapipe; one VPL of 256 moved differently would give ~1e-4).
//! Without an adapter the test says it skipped, unless VPL_REQUIRE_GPU=1.
#![cfg(feature = "gpu")]

use vpl_bench::pipeline::{BackendKind, PipelineSpec, ShadingSpec, VisibilitySpec};
use vpl_core::{Budget, GeometryClamp, Mode, Params, SceneSetup};
use vpl_sampling::Registry;

fn spec(sampler: &str, backend: BackendKind, visibility: VisibilitySpec, vpls: usize, clamp: GeometryClamp) -> PipelineSpec {
    PipelineSpec {
        sampler: sampler.into(),
        params: Params::new(),
        budget: Budget::new(vpls, 5),
        visibility,
        shading: ShadingSpec::Interleaved { filter: true },
        clamp: vpl_render::Clamp::Value(clamp),
        compensation: 0,
        mode: Mode::Indirect,
        direct_samples: 1,
        seed: 3,
        backend: backend.name().into(),
    }
}

#[test]
fn gpu_backend_renders_the_cpu_backends_frames() {
    let setup = SceneSetup::builtin("office").unwrap();
    let vpls = 256;
    let clamp = GeometryClamp::for_scene_area(vpls, setup.scene.surface_area());
    for (sampler, vis) in [("smc", VisibilitySpec::ShadowMaps(64)), ("ir", VisibilitySpec::RayTraced)] {
        let registry = Registry::builtin();
        let mut gpu =
            match spec(sampler, BackendKind::Gpu, vis, vpls, clamp).build(&registry, &vpl_bench::pipeline::backends(), &setup.scene) {
                Ok(p) => p,
                Err(e) if std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("VPL_REQUIRE_GPU=1 but {e}"),
                Err(e) => {
                    eprintln!("skipped: {e}");
                    return;
                }
            };
        eprintln!("adapter: {}", gpu.backend().device().unwrap());
        let mut cpu =
            spec(sampler, BackendKind::Cpu, vis, vpls, clamp).build(&registry, &vpl_bench::pipeline::backends(), &setup.scene).unwrap();
        for f in 0..3u32 {
            let (scene, camera) = setup.frame(f * 10).unwrap();
            let camera = camera.with_resolution((96, 54)).unwrap();
            let a = cpu.render(&scene, &camera, f as u64, f as f32 / 3.0).unwrap();
            let b = gpu.render(&scene, &camera, f as u64, f as f32 / 3.0).unwrap();
            assert_eq!(a.moved, b.moved, "{sampler} frame {f}: VPLs moved");
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for (x, y) in a.image.data.iter().zip(&b.image.data) {
                num += (*x - *y).length_squared() as f64;
                den += x.length_squared() as f64;
            }
            eprintln!("{sampler} frame {f}: relative squared error {:.3e}, {} moved", num / den, a.moved);
            assert!(den > 0.0 && num / den <= 1e-6, "{sampler} frame {f}: relative squared error {:e}", num / den);
        }
    }
}

/// Runs `vpl` with `args` and `--out` a fresh folder named after `name`;
/// `None` (the test skips) when no adapter is found, unless VPL_REQUIRE_GPU=1.
fn vpl_on_the_gpu(name: &str, args: &[&str]) -> Option<(std::process::Output, std::path::PathBuf)> {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vpl")).args(args).arg("--out").arg(&dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && !std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") && stderr.contains("adapter") {
        eprintln!("skipped: {stderr}");
        return None;
    }
    assert!(out.status.success(), "{stderr}");
    Some((out, dir))
}

/// `vpl bench-gpu` measures SMC on the host and wholly on the device in one
/// run, side by side; the device's step is one submission that reads back
/// only the VPLs and the statistics.
#[test]
fn bench_gpu_measures_smc_on_the_host_and_on_the_device() {
    let args = ["bench-gpu", "--scene", "cornell", "--size", "48x36", "--vpls", "64", "--frames", "2", "--smc", "host,device"];
    let Some((out, dir)) = vpl_on_the_gpu("vpl-bench-gpu", &args) else { return };
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("gpu_bench.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    let places: Vec<&str> = rows.iter().map(|r| r["smc"].as_str().unwrap()).collect();
    assert_eq!(places, ["host", "device"]);
    let device = &rows[1]["sampling_traffic"];
    assert_eq!(device["submissions"], 1, "{device}");
    assert_eq!(device["reads"], 1, "{device}");
    // The VPL rows and statistics, and the stages' timestamps where the
    // adapter writes them (88 B in 6 rows of 16 B).
    let down = device["bytes_down"].as_u64().unwrap();
    assert!(down == 3 * 64 * 16 + 64 || down == 3 * 64 * 16 + 64 + 96, "{device}");
    let host = &rows[0]["sampling_traffic"];
    assert!(host["submissions"].as_u64().unwrap() > 1, "{host}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("| `cornell` | host |") && stdout.contains("| `cornell` | device |"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `vpl table2 --backend gpu` runs SMC wholly on the device by default, its
/// sampler's columns timed there (each positive where the adapter writes
/// timestamps, as lavapipe and llvmpipe's GL do), and says so.
#[test]
fn table2_on_the_gpu_times_the_devices_smc() {
    let args = ["table2", "--backend", "gpu", "--scene", "office", "--size", "64x36", "--frames", "2"];
    let Some((_, dir)) = vpl_on_the_gpu("vpl-table2-gpu", &args) else { return };
    let md = std::fs::read_to_string(dir.join("table2.md")).unwrap();
    assert!(md.contains("wholly on the device"), "{md}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("table2.json")).unwrap()).unwrap();
    let row = &json[0];
    eprintln!("{row}");
    for key in ["cand_sampling", "cand_resampling", "indirect_visibility", "radiosity", "knn", "sampling_total"] {
        let v = row[key].as_f64().unwrap();
        assert!(v > 0.0 && v.is_finite(), "{key} = {v}");
    }
    let parts: f64 =
        ["cand_sampling", "cand_resampling", "indirect_visibility", "radiosity", "knn"].iter().map(|k| row[*k].as_f64().unwrap()).sum();
    // Medians of each column: their sum is near the median total, not equal.
    assert!(parts <= 1.5 * row["sampling_total"].as_f64().unwrap(), "{row}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `vpl track --backend gpu` writes the CSV of `--backend cpu` with the
/// device's estimate: per pixel and channel |Δm| / √(se₁² + se₂²) ≤ 4 (the
/// same estimator over other streams; 12 comparisons, fixed seeds), the
/// same samples; a scene with layered materials is refused (exit 2) until
/// `--materials diffuse`.
#[test]
fn track_on_the_gpu_agrees_with_the_cpu() {
    let csv = |backend: &str, scene: &str, extra: &[&str]| {
        let base =
            ["track", "--scene", scene, "--pixel", "10,10", "--pixel", "100,50", "--pixel", "150,80", "--spp", "8192", "--size", "160x90"];
        std::process::Command::new(env!("CARGO_BIN_EXE_vpl")).args(base).args(["--backend", backend]).args(extra).output().unwrap()
    };
    let gpu = csv("gpu", "office", &[]);
    let stderr = String::from_utf8_lossy(&gpu.stderr);
    if !gpu.status.success() && !std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") && stderr.contains("adapter") {
        return eprintln!("skipped: {stderr}");
    }
    assert!(gpu.status.success(), "{stderr}");
    let cpu = csv("cpu", "office", &[]);
    let rows = |o: &std::process::Output| -> Vec<Vec<f64>> {
        String::from_utf8_lossy(&o.stdout).lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect()
    };
    let (g, c) = (rows(&gpu), rows(&cpu));
    assert_eq!(g.len(), 3);
    for (a, b) in g.iter().zip(&c) {
        assert_eq!((a[0], a[1], a[8]), (b[0], b[1], b[8]));
        for ch in 2..5 {
            let se = (a[ch + 3].powi(2) + b[ch + 3].powi(2)).sqrt();
            assert!(se > 0.0 && (a[ch] - b[ch]).abs() <= 4.0 * se, "pixel {},{}: {} vs {} ± {se}", a[0], a[1], a[ch], b[ch]);
        }
    }
    let layered = csv("gpu", "glass", &[]);
    assert_eq!(layered.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&layered.stderr).contains("--materials diffuse"));
    assert!(csv("gpu", "glass", &["--materials", "diffuse"]).status.success());
}

/// `vpl bench-gpu` on a Table 1 sequence also times one truth frame on the
/// CPU and on the device, side by side, into its report and JSON.
#[test]
fn bench_gpu_times_the_ground_truth_on_both_sides() {
    let args =
        ["bench-gpu", "--scene", "office", "--size", "48x36", "--vpls", "64", "--frames", "1", "--smc", "host", "--truth-spp", "512"];
    let Some((out, dir)) = vpl_on_the_gpu("vpl-bench-gpu-truth", &args) else { return };
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("gpu_bench.json")).unwrap()).unwrap();
    let truth = json["truth"].as_array().unwrap();
    assert_eq!(truth.len(), 1);
    assert_eq!((truth[0]["row"].as_str(), truth[0]["pixels"].as_u64(), truth[0]["spp"].as_u64()), (Some("office"), Some(8), Some(512)));
    assert!(truth[0]["cpu_seconds"].as_f64().unwrap() > 0.0 && truth[0]["gpu_seconds"].as_f64().unwrap() > 0.0);
    assert!(String::from_utf8_lossy(&out.stdout).contains("| `office` | 8 | 512 |"));
    let _ = std::fs::remove_dir_all(&dir);
}
