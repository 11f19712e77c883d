//! Table 1's ground truth on the GPU against the CPU path tracer: the
//! harness's truth units of every sequence, at its first and middle
//! quick-profile frames (sequences on real geometry where its model is
//! here), made with `--backend cpu` (`track_with`) and
//! `--backend gpu` (`vpl_gpu::GpuTracker`, other streams).
//!
//! Both are means of independent samples of one estimator, so per tracked
//! pixel and channel z = |m_cpu − m_gpu| / √(se_cpu² + se_gpu²) is about
//! standard normal. Tolerances: every |z| ≤ 4 (the bound; over the
//! ~300 comparisons a false alarm has odds of about 2 % under normality,
//! and the seeds are fixed), and the mean of z² ≤ 1.5 (χ² over ~300
//! degrees of freedom stays below 1.27 × its count with odds 0.999; a bias
//! of one standard error in every pixel doubles it). Pixels where both
//! estimates are zero must agree exactly.
#![cfg(feature = "gpu")]

use vpl_bench::pipeline::BackendKind;
use vpl_bench::table1::rows;
use vpl_bench::table1::truth::Truth;
use vpl_bench::table1::{self, RowRun, Table1Spec};

#[test]
fn gpu_truth_matches_the_cpu_truth_on_every_sequence() {
    match vpl_gpu::GpuContext::new() {
        Ok(c) => eprintln!("adapter: {}", c.describe()),
        Err(e) if std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("VPL_REQUIRE_GPU=1 but {e}"),
        Err(e) => return eprintln!("skipped: {e}"),
    }
    let mut cpu_spec = Table1Spec::quick();
    cpu_spec.truth_spp = 4096;
    cpu_spec.size = (160, 120);
    let gpu_spec = Table1Spec { backend: BackendKind::Gpu, ..cpu_spec.clone() };
    let (mut cpu, mut gpu) = (Truth::new(), Truth::new());
    let (mut z2, mut n, mut worst) = (0.0f64, 0usize, (0.0f64, String::new()));
    let mut seen = 0;
    for RowRun { id, start, end } in &cpu_spec.rows {
        let row = rows::row(id).unwrap();
        seen += 1;
        for frame in [*start, (start + end) / 2] {
            let (a, b) = (cpu.unit(&cpu_spec, &row, frame).unwrap(), gpu.unit(&gpu_spec, &row, frame).unwrap());
            assert_eq!((a.mean.len(), b.samples), (b.mean.len(), 4096));
            // The unit names the adapter that made it (cost.md quotes it).
            assert!(a.device.is_none() && b.device.as_ref().is_some_and(|d| !d.is_empty()));
            for p in 0..a.mean.len() {
                for c in 0..3 {
                    let (ma, mb) = (a.mean[p][c] as f64, b.mean[p][c] as f64);
                    let se = ((a.stderr[p][c] as f64).powi(2) + (b.stderr[p][c] as f64).powi(2)).sqrt();
                    if se == 0.0 {
                        assert_eq!(ma, mb, "{id} frame {frame} pixel {p}: {ma} without variance against {mb}");
                        continue;
                    }
                    let z = (ma - mb) / se;
                    z2 += z * z;
                    n += 1;
                    if z.abs() > worst.0 {
                        worst = (z.abs(), format!("{id} frame {frame} pixel {p} channel {c}: {ma} vs {mb} ± {se}"));
                    }
                }
            }
        }
        eprintln!(
            "{id}: CPU {:.2} s, GPU {:.2} s a frame",
            a_seconds(&mut cpu, &cpu_spec, &row, *start),
            a_seconds(&mut gpu, &gpu_spec, &row, *start)
        );
    }
    eprintln!("{seen} sequences, {n} comparisons: mean z² {:.3}, worst |z| {:.2} ({})", z2 / n as f64, worst.0, worst.1);
    // Every sequence whose scene is here: the built-in ones always, those
    // on real geometry where its model is (the rest are named).
    for (id, why) in table1::skipped_rows() {
        eprintln!("{id}: not run ({why})");
    }
    let built_in = rows::rows().iter().filter(|r| r.file.is_none()).count();
    assert!(seen >= built_in && seen + table1::skipped_rows().len() == rows::rows().len(), "{seen} sequences ran");
    assert!(worst.0 <= 4.0, "|z| {:.2} at {}", worst.0, worst.1);
    assert!(z2 / n as f64 <= 1.5, "mean z² {:.3} over {n}", z2 / n as f64);
}

/// The wall time of one more truth unit (the scene already loaded).
fn a_seconds(t: &mut Truth, spec: &Table1Spec, row: &rows::Row, frame: u32) -> f64 {
    t.unit(spec, row, frame).unwrap().seconds
}
