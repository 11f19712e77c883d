//! Table 1 end to end on a tiny run: units, merge, files; a run split into
//! two shards merges to the same bits as the unsplit run.

use std::path::{Path, PathBuf};
use vpl_bench::table1::{self, RowRun, Shard, Table1Error, Table1Spec};
use vpl_sampling::Registry;

fn tiny() -> Table1Spec {
    Table1Spec {
        profile: "test".into(),
        rows: vec![RowRun { id: "maze".into(), start: 300, end: 303 }],
        methods: vec!["ir".into(), "smc".into()],
        size: (64, 48),
        truth_spp: 512,
        max_depth: 5,
        shadow_map_res: 32,
        seed: 3,
        seeds: 2,
        backend: vpl_bench::pipeline::BackendKind::Cpu,
    }
}

fn fresh(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vpl-table1-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn read(dir: &Path, f: &str) -> String {
    std::fs::read_to_string(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"))
}

#[test]
fn a_tiny_run_merges_and_two_shards_give_the_same_bits() {
    let reg = Registry::builtin();
    let spec = tiny();
    let whole = fresh("whole");
    let s = table1::run(&reg, &spec, &whole, Shard::ALL, &mut |_| {}).unwrap();
    // Two methods × two seeds, and three frames of truth.
    assert_eq!((s.ran, s.kept, s.total_units), (7, 0, 7));
    let r = table1::merge(&whole).unwrap();
    let row = &r.rows[0];
    assert_eq!(row.truth.len(), 3);
    assert_eq!(row.methods.len(), 2);
    for m in &row.methods {
        assert!(m.error.e.is_finite() && m.error.e > 0.0 && m.error.e_prime.is_finite(), "{m:?}");
        assert_eq!((m.error.count, m.error.count_prime), (48, 32));
        assert_eq!((m.luminance.len(), m.e_per_seed.len()), (2, 2));
        // The two seeds are different runs, and the pooled |E| is their mean.
        assert_ne!(m.luminance[0], m.luminance[1], "{}: the seeds gave the same run", m.method);
        assert!((m.error.e - (m.e_per_seed[0] + m.e_per_seed[1]) / 2.0).abs() < 1e-12);
        let ci = m.intervals;
        assert!(ci.e.lo <= m.error.e && m.error.e <= ci.e.hi && ci.e.lo < ci.e.hi, "{ci:?}");
        assert!(ci.bias.lo <= m.error.bias && m.error.bias <= ci.bias.hi, "{ci:?}");
        let split = m.split.expect("two seeds split the error");
        assert!(split.mse > 0.0 && (0.0..=1.0).contains(&split.noise_share()));
    }
    assert_eq!(row.comparisons.len(), 1);
    assert_eq!(row.comparisons[0].method, "ir");
    // The truth is not black: the tracked pixels see lit surfaces.
    assert!(row.truth.iter().flatten().filter(|l| **l > 0.0).count() >= 12, "{:?}", row.truth);
    let md = read(&whole, "table1.md");
    assert!(md.contains("| `maze` |") && md.contains("paper SMC") && md.contains("0.0221"), "{md}");
    assert!(md.contains("bias and how much noise") && md.contains("bootstrap"), "{md}");
    assert!(read(&whole, "table1.csv").lines().count() == 3);
    assert!(whole.join("fig7_maze.png").exists());
    // The wall times and the estimate of the full profile, apart from the tables (they differ run to run).
    let cost = read(&whole, "cost.md");
    assert!(cost.contains("for the full profile of these methods on maze") && cost.contains("ground truth)"), "{cost}");

    // A second call finds every unit done and keeps it.
    let again = table1::run(&reg, &spec, &whole, Shard::ALL, &mut |_| {}).unwrap();
    assert_eq!((again.ran, again.kept), (0, 7));

    let split = fresh("split");
    let a = table1::run(&reg, &spec, &split, Shard { index: 0, count: 2 }, &mut |_| {}).unwrap();
    // Half the units are missing before the second shard runs, and the status says whose.
    assert!(matches!(table1::merge(&split), Err(Table1Error::Missing { missing: 3, total: 7, .. })));
    let st = table1::status(&split, 2).unwrap();
    assert_eq!(st.iter().map(|s| (s.shard.index, s.done, s.total)).collect::<Vec<_>>(), [(0, 4, 4), (1, 0, 3)]);
    let b = table1::run(&reg, &spec, &split, Shard { index: 1, count: 2 }, &mut |_| {}).unwrap();
    assert_eq!((a.ran, b.ran), (4, 3));
    // A merge that fails on its last output writes none of them (the old
    // merge left table1.md, .csv, .json, runs.csv and cost.md behind).
    std::fs::create_dir(split.join("fig7.csv")).unwrap();
    let e = table1::merge(&split).unwrap_err().to_string();
    assert!(e.contains("fig7.csv") && e.contains("a directory"), "{e}");
    let mut left: Vec<String> = std::fs::read_dir(&split).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    assert_eq!(left, ["fig7.csv", "spec.json", "units"], "a failed merge left files");
    std::fs::remove_dir(split.join("fig7.csv")).unwrap();
    table1::merge(&split).unwrap();
    for f in ["table1.json", "table1.md", "table1.csv", "fig7.csv"] {
        assert!(read(&whole, f) == read(&split, f), "{f} differs between the whole and the sharded run");
    }

    // Another spec into the same folder is refused, naming the setting.
    let other = Table1Spec { seed: 4, ..spec.clone() };
    let e = table1::run(&reg, &other, &split, Shard::ALL, &mut |_| {}).unwrap_err();
    assert!(matches!(e, Table1Error::SpecMismatch(..)) && e.to_string().contains("seed: 3 (this run: 4)"), "{e}");
    // Without spec.json, the units themselves refuse the other settings.
    std::fs::remove_file(split.join("spec.json")).unwrap();
    let e = table1::run(&reg, &other, &split, Shard::ALL, &mut |_| {}).unwrap_err();
    assert!(matches!(e, Table1Error::UnitMismatch(..)) && e.to_string().contains("units/maze/") && e.to_string().contains("seed"), "{e}");
    assert!(!split.join("spec.json").exists(), "a refused run wrote spec.json");
    // A unit copied from a run at another size is refused when merging, naming the file and the size.
    let small = fresh("small");
    let at_other_size = Table1Spec { size: (spec.size.0, spec.size.1 + 8), ..spec.clone() };
    table1::run(&reg, &at_other_size, &small, Shard::ALL, &mut |_| {}).unwrap();
    std::fs::copy(small.join("units/maze/ir_seed1.json"), whole.join("units/maze/ir_seed1.json")).unwrap();
    let e = table1::merge(&whole).unwrap_err().to_string();
    assert!(e.contains("ir_seed1.json") && e.contains("size"), "{e}");
    // A number beyond single precision (it read as infinity, and the table
    // printed inf and NaN with success) is refused naming the unit; the
    // earlier results stay as they were.
    let before = read(&whole, "table1.md");
    std::fs::copy(split.join("units/maze/ir_seed1.json"), whole.join("units/maze/ir_seed1.json")).unwrap();
    let unit = whole.join("units/maze/smc_seed0.json");
    let mut v: serde_json::Value = serde_json::from_str(&read(&whole, "units/maze/smc_seed0.json")).unwrap();
    v["tracked"][0][0][0] = serde_json::json!(1e39);
    std::fs::write(&unit, serde_json::to_string(&v).unwrap()).unwrap();
    let e = table1::merge(&whole).unwrap_err().to_string();
    assert!(e.contains("smc_seed0.json") && e.contains("not a finite single-precision number"), "{e}");
    assert_eq!(read(&whole, "table1.md"), before);
    std::fs::remove_dir_all(&small).unwrap();
    std::fs::remove_dir_all(&whole).unwrap();
    std::fs::remove_dir_all(&split).unwrap();
}

/// A run of SMC's variants alone (how a researcher compares estimators)
/// has no other method for the target's table: its cells say so with a
/// dash, not with a NaN.
#[test]
fn a_run_of_smc_variants_alone_compares_with_nothing() {
    let reg = Registry::builtin();
    let spec = Table1Spec { methods: vec!["smc".into(), "smc:placement=random".into()], seeds: 1, ..tiny() };
    let dir = fresh("variants");
    table1::run(&reg, &spec, &dir, Shard::ALL, &mut |_| {}).unwrap();
    table1::merge(&dir).unwrap();
    let md = read(&dir, "table1.md");
    assert!(md.contains("SMC (placement=random)"), "{md}");
    let target = md.split("## The target").nth(1).expect("the target's table");
    assert!(!target.contains("NaN") && target.contains("| `maze` | "), "{target}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn specs_and_shards_are_checked() {
    let mut s = tiny();
    s.rows[0].end = 100_000;
    assert!(s.validate(&Registry::builtin()).unwrap_err().to_string().contains("do not fit maze"));
    let mut s = tiny();
    s.methods = vec!["nope".into()];
    assert!(s.validate(&Registry::builtin()).unwrap_err().to_string().contains("unknown method 'nope'"));
    let mut s = tiny();
    s.rows[0].id = "sponza-crytek".into();
    assert!(s.validate(&Registry::builtin()).unwrap_err().to_string().contains("unknown sequence"));
    // 10,000 methods exhausted memory; a method or sequence listed twice is refused too.
    let mut s = tiny();
    s.methods = (0..10_000).map(|i| format!("m{i}")).collect();
    assert!(s.validate_settings().unwrap_err().to_string().contains("at most 64 methods"));
    let mut s = tiny();
    s.methods = vec!["ir".into(), "ir".into()];
    assert!(s.validate_settings().unwrap_err().to_string().contains("'ir' is listed twice"));
    let mut s = tiny();
    s.rows.push(s.rows[0].clone());
    assert!(s.validate_settings().unwrap_err().to_string().contains("'maze' is listed twice"));
    let mut s = tiny();
    s.seeds = 0;
    assert!(s.validate(&Registry::builtin()).unwrap_err().to_string().contains("seeds"));
    assert!("1/2".parse::<Shard>().is_ok());
    for bad in ["2/2", "1", "a/b", "0/0"] {
        assert!(bad.parse::<Shard>().is_err(), "{bad}");
    }
    // Units go round-robin: every unit to exactly one of three shards.
    let units = Table1Spec::quick().units();
    for k in 0..units.len() {
        assert_eq!((0..3).filter(|&i| Shard { index: i, count: 3 }.owns(k)).count(), 1);
    }
    // The quick profile's windows hold the paper's five rows, then the two on
    // real geometry where their models are here; three seeds.
    let q = Table1Spec::quick();
    q.validate(&Registry::builtin()).unwrap();
    let skipped: Vec<&str> = table1::skipped_rows().iter().map(|(id, _)| *id).collect();
    let expected: Vec<&str> = ["office", "courtyard", "maze", "atrium", "courtyard-sun", "sponza", "munich"]
        .into_iter()
        .filter(|id| !skipped.contains(id))
        .collect();
    assert_eq!(q.rows.iter().map(|r| r.id.as_str()).collect::<Vec<_>>(), expected);
    assert!(skipped.iter().all(|id| ["sponza", "munich"].contains(id)), "{skipped:?}");
    assert_eq!(q.seeds, 3);
}
