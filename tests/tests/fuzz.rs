//! The loader fuzz targets, bounded: every kept regression input is replayed
//! and must end in a finite image or a one-line refusal, then
//! `VPL_FUZZ_EXECS` fresh mutations per target (default 40, one test a
//! target) must too.
//! `cargo xtask fuzz --seconds N` runs them for longer.

use vpl_tests::fuzz::{self, Outcome, Target};

fn scratch(name: &str) -> std::path::PathBuf {
    let d = vpl_tests::scratch_dir("fuzz").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn kept_regressions_stay_fixed() {
    fuzz::quiet_panics();
    let mut replayed = 0;
    for t in Target::ALL {
        let seeds = fuzz::seeds(t);
        let dir = scratch(&format!("replay-{}", t.name()));
        for (path, seed, input) in fuzz::regressions(t) {
            let seed = seeds.get(seed).unwrap_or_else(|| panic!("{}: no seed {seed}", path.display()));
            for variant in 0..4 {
                if let Outcome::Finding(what) = fuzz::run_one(t, seed, &input, &dir, variant) {
                    panic!("{} (renderer {variant}): {what}", path.display());
                }
            }
            replayed += 1;
        }
    }
    assert!(replayed > 0, "tests/data/fuzz-regressions holds no inputs");
}

/// `VPL_FUZZ_EXECS` fresh mutations of `t` (default 40) keep the promises.
fn fresh_mutations_keep_the_promises(t: Target) {
    fuzz::quiet_panics();
    let execs: u64 = std::env::var("VPL_FUZZ_EXECS").ok().and_then(|v| v.parse().ok()).unwrap_or(40);
    let report = fuzz::run(t, 7, 0, &scratch(t.name()), |done| done >= execs);
    let f: Vec<String> = report.findings.iter().map(|f| format!("execution {}: {}", f.execution, f.what)).collect();
    assert!(f.is_empty(), "{}: {}", t.name(), f.join("; "));
    assert_eq!(report.executions, execs);
}

/// One test a target, so that a test runner spreads them over its threads.
macro_rules! fresh_mutations {
    ($($name:ident: $target:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                fresh_mutations_keep_the_promises(Target::$target);
            }
        )*
        /// Every target has its test.
        #[test]
        fn every_target_has_a_fresh_mutation_test() {
            let named = [$(Target::$target),*];
            assert!(Target::ALL.iter().all(|t| named.contains(t)), "a target without a test");
        }
    };
}

fresh_mutations!(
    fresh_obj: Obj,
    fresh_mtl: Mtl,
    fresh_toml: Toml,
    fresh_exr: Exr,
    fresh_mitsuba: Mitsuba,
    fresh_ply: Ply,
    fresh_gltf: Gltf,
    fresh_glb: Glb,
    fresh_sequence: Sequence,
    fresh_table1: Table1,
);

/// Each seed, unmutated, renders (or merges) with every renderer: a seed
/// that is refused would make its mutations test the refusal only.
#[test]
fn unmutated_seeds_are_accepted() {
    fuzz::quiet_panics();
    for t in Target::ALL {
        let dir = scratch(&format!("seed-{}", t.name()));
        for (k, seed) in fuzz::seeds(t).iter().enumerate() {
            for variant in 0..4 {
                let outcome = fuzz::run_one(t, seed, &seed.files[0].1, &dir, variant);
                assert_eq!(outcome, Outcome::Accepted, "{} seed {k} (renderer {variant})", t.name());
            }
        }
    }
}
