//! The command line's sampler flags come from the registry: a program's own
//! sampler, registered with its keys, gets `--KEY VALUE` flags like the
//! built-ins (whose flags keep their names), and a flag the chosen sampler
//! does not read is refused in one line.

use std::sync::atomic::{AtomicU32, Ordering};
use vpl_sampling::vpl_core::ParamKey;
use vpl_sampling::{Registry, SamplerEntry};

/// The `my-knob` value the last build of `knob-ir` read.
static KNOB: AtomicU32 = AtomicU32::new(0);

/// IR under another name, reading one key of its own.
fn registry() -> Registry {
    const KEYS: &[ParamKey] = &[ParamKey { key: "my-knob", default: "3", about: "a knob of the user's sampler" }];
    let entry = SamplerEntry::new("knob-ir", "IR with a knob", |cx, p| {
        KNOB.store(
            p.get_or("my-knob", 3u32).map_err(|source| vpl_sampling::SamplingError::Param { name: "knob-ir".into(), source })?,
            Ordering::SeqCst,
        );
        cx.build("ir", p)
    })
    .with_keys(KEYS);
    Registry::builtin().with(entry).unwrap()
}

fn render(registry: &Registry, extra: &[&str], out: &std::path::Path) -> i32 {
    let mut args: Vec<String> =
        ["vpl", "render", "--scene", "cornell", "--method", "vpl", "--vpls", "16", "--size", "8x8", "--quiet"].map(String::from).to_vec();
    args.extend(extra.iter().map(|s| s.to_string()));
    args.extend(["--out".to_string(), out.to_string_lossy().into_owned()]);
    vpl_cli::run(registry, &args)
}

#[test]
fn a_registered_samplers_keys_are_flags() {
    let dir = std::env::temp_dir().join(format!("vpl-sampler-flags-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let r = registry();
    assert_eq!(render(&r, &["--sampler", "knob-ir", "--my-knob", "7"], &dir.join("a.exr")), 0);
    assert_eq!(KNOB.load(Ordering::SeqCst), 7);
    assert!(dir.join("a.exr").is_file());
    // `--set` still reaches the same key.
    assert_eq!(render(&r, &["--sampler", "knob-ir", "--set", "my-knob=5"], &dir.join("b.exr")), 0);
    assert_eq!(KNOB.load(Ordering::SeqCst), 5);
    // A built-in sampler does not read it; nor may the flag be given twice over.
    assert_eq!(render(&r, &["--sampler", "ir", "--my-knob", "7"], &dir.join("c.exr")), 2);
    assert!(!dir.join("c.exr").exists());
    assert_eq!(render(&r, &["--sampler", "knob-ir", "--my-knob", "7", "--set", "my-knob=8"], &dir.join("d.exr")), 2);
    // The built-ins' flags keep their names: a switch and a valued flag.
    assert_eq!(render(&r, &["--sampler", "ir", "--fresh-paths", "--path-sampling", "halton"], &dir.join("e.exr")), 0);
    assert_eq!(render(&r, &["--sampler", "smc", "--m-max", "4", "--warmup", "2"], &dir.join("f.exr")), 0);
    // Without the entry, the flag does not exist.
    assert_eq!(render(&Registry::builtin(), &["--sampler", "ir", "--my-knob", "7"], &dir.join("g.exr")), 2);
    std::fs::remove_dir_all(&dir).unwrap();
}
