//! `vpl-fuzz`: runs the loader fuzz targets for a while and reports the
//! executions and what they found (`cargo xtask fuzz` runs it).
//!
//! ```text
//! vpl-fuzz [--target obj|mtl|toml|exr|mitsuba|ply|gltf|glb|sequence|table1|all] [--seconds N] [--executions N] [--seed S] [--first I]
//!          [--findings DIR] [--inputs DIR]
//! ```
//!
//! The time is shared equally by the targets. Findings are written to
//! `DIR/<target>/<seed>-<execution>` (default `target/fuzz-findings`), ready
//! to be moved into `tests/data/fuzz-regressions/`. `--executions N` stops
//! after N executions per target; `--inputs DIR` writes every input it makes
//! (to reproduce execution I of seed S: `--seed S --first I --executions 1
//! --inputs DIR`). Exit 1 when something was found.

use std::path::PathBuf;
use std::time::{Duration, Instant};
use vpl_tests::fuzz::{self, Target};

fn main() {
    let mut targets = Target::ALL.to_vec();
    let mut seconds = 60.0f64;
    let mut seed = 1u64;
    let mut first = 0u64;
    let mut executions = u64::MAX;
    let mut inputs: Option<PathBuf> = None;
    let mut findings_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/fuzz-findings");
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    let fail = |m: String| -> ! {
        eprintln!("vpl-fuzz: error: {m}");
        std::process::exit(2)
    };
    while i < args.len() {
        let value = args.get(i + 1).cloned().unwrap_or_else(|| fail(format!("{} needs a value", args[i])));
        match args[i].as_str() {
            "--target" if value == "all" => targets = Target::ALL.to_vec(),
            "--target" => targets = vec![Target::parse(&value).unwrap_or_else(|| fail(format!("unknown target '{value}'")))],
            "--seconds" => {
                seconds = value.parse().ok().filter(|s: &f64| s.is_finite() && *s > 0.0).unwrap_or_else(|| fail("--seconds".into()))
            }
            "--seed" => seed = value.parse().unwrap_or_else(|_| fail("--seed".into())),
            "--first" => first = value.parse().unwrap_or_else(|_| fail("--first".into())),
            "--findings" => findings_dir = PathBuf::from(value),
            "--executions" => executions = value.parse().unwrap_or_else(|_| fail("--executions".into())),
            "--inputs" => inputs = Some(PathBuf::from(value)),
            a => fail(format!("unknown argument '{a}'")),
        }
        i += 2;
    }
    fuzz::quiet_panics();
    let scratch = std::env::temp_dir().join(format!("vpl-fuzz-{}", std::process::id()));
    let share = Duration::from_secs_f64(seconds / targets.len() as f64);
    let mut total = 0u64;
    let mut found = 0usize;
    for t in targets {
        let start = Instant::now();
        if let Some(dir) = &inputs {
            let seeds = fuzz::seeds(t);
            let _ = std::fs::create_dir_all(dir.join(t.name()));
            for i in first..first.saturating_add(executions.min(10_000)) {
                let (k, input) = fuzz::input(t, &seeds, seed, i);
                let _ = std::fs::write(dir.join(t.name()).join(format!("{k}-{i}")), input);
            }
        }
        let report = fuzz::run(t, seed, first, &scratch.join(t.name()), |done| done >= executions || start.elapsed() >= share);
        let secs = start.elapsed().as_secs_f64();
        println!(
            "{}: {} executions in {secs:.0} s ({:.0}/s): {} accepted, {} refused with one line, {} findings",
            t.name(),
            report.executions,
            report.executions as f64 / secs,
            report.accepted,
            report.refused,
            report.findings.len()
        );
        for f in &report.findings {
            let dir = findings_dir.join(t.name());
            let _ = std::fs::create_dir_all(&dir);
            let path = dir.join(format!("{}-{}", f.seed, f.execution));
            let _ = std::fs::write(&path, &f.input);
            println!("  finding {}: {} ({})", f.execution, f.what, path.display());
        }
        total += report.executions;
        found += report.findings.len();
    }
    let _ = std::fs::remove_dir_all(&scratch);
    println!("total: {total} executions, {found} findings (seed {seed}, first execution {first})");
    std::process::exit(if found > 0 { 1 } else { 0 });
}
