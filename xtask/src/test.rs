//! `cargo xtask test`: the whole suite, and the tests that took longest.
//!
//! With cargo-nextest installed (`cargo install cargo-nextest --locked`) the
//! unit, integration and example tests run under it: each test is a process
//! of its own, two binaries' tests share the cores instead of one binary's
//! slowest test holding up the next binary, and each test's wall time comes
//! back in `target/nextest/default/junit.xml` (under the workspace's root),
//! from which the slowest are listed. nextest does not run doctests; `cargo test --doc` runs them
//! after. Without nextest, `cargo test --workspace` runs everything, as it
//! always did, and no times are listed (libtest reports a test's time only
//! on nightly). `--cargo-test` asks for that path with nextest installed.
//!
//! Arguments are passed on to both runners (`-p vpl-core`, a filter).

use std::path::Path;

/// How many of the slowest tests the summary lists.
const SLOWEST: usize = 15;

pub(crate) fn test(args: &[String]) -> Result<(), String> {
    let plain = args.iter().any(|a| a == "--cargo-test");
    let args: Vec<&String> = args.iter().filter(|a| *a != "--cargo-test").collect();
    if plain || !nextest_installed() {
        if !plain {
            eprintln!("xtask: cargo-nextest is not installed: running `cargo test` (no per-test times)");
        }
        let mut c = crate::cargo();
        c.args(["test", "--workspace", "--no-fail-fast"]).args(&args);
        return crate::run(c, "cargo test");
    }
    let mut c = crate::cargo();
    c.args(["nextest", "run", "--workspace", "--no-fail-fast"]).args(&args);
    let tests = crate::run(c, "cargo nextest run");
    // nextest keeps its store under the workspace's own `target/` (the
    // `[store]` of .config/nextest.toml), wherever cargo builds.
    match slowest(&crate::root().join("target").join("nextest").join("default").join("junit.xml"), SLOWEST) {
        Ok(table) => eprint!("{table}"),
        Err(e) => eprintln!("xtask: no test times: {e}"),
    }
    // The whole workspace, as the tests above: leaving a member out (say
    // vpl-python, which has no doctests) changes the features cargo unifies
    // and rebuilds every crate under the other set.
    let mut c = crate::cargo();
    c.args(["test", "--workspace", "--doc", "--no-fail-fast"]).args(&args);
    let doc = crate::run(c, "cargo test --doc");
    tests.and(doc)
}

/// Whether `cargo nextest` answers.
fn nextest_installed() -> bool {
    crate::cargo()
        .args(["nextest", "--version"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The `n` slowest tests of a JUnit report, as a table.
fn slowest(junit: &Path, n: usize) -> Result<String, String> {
    let xml = std::fs::read_to_string(junit).map_err(|e| format!("{}: {e}", junit.display()))?;
    let mut cases = test_cases(&xml);
    if cases.is_empty() {
        return Err(format!("{}: no test cases", junit.display()));
    }
    cases.sort_by(|a, b| b.2.total_cmp(&a.2).then_with(|| a.0.cmp(&b.0)));
    let total: f64 = cases.iter().map(|c| c.2).sum();
    let mut out = format!("xtask: the {} slowest of {} tests ({total:.0} s of test time in all):\n", n.min(cases.len()), cases.len());
    for (binary, name, secs) in cases.iter().take(n) {
        out.push_str(&format!("xtask: {secs:>8.1} s  {binary} {name}\n"));
    }
    Ok(out)
}

/// (binary, test, seconds) of every `<testcase>` of a JUnit report.
/// nextest writes one element per test with `name`, `classname` (the test
/// binary) and `time` attributes, quoted and escaped as XML requires.
fn test_cases(xml: &str) -> Vec<(String, String, f64)> {
    xml.split("<testcase ")
        .skip(1)
        .filter_map(|element| {
            let head = &element[..element.find('>')?];
            let time = attribute(head, "time")?.parse::<f64>().ok()?;
            Some((attribute(head, "classname").unwrap_or_default(), attribute(head, "name")?, time))
        })
        .collect()
}

/// The unescaped value of attribute `key` in an element's head.
fn attribute(head: &str, key: &str) -> Option<String> {
    let mut rest = head;
    loop {
        let at = rest.find(&format!("{key}=\""))?;
        // A whole attribute name: at the start or after whitespace.
        let whole = at == 0 || rest[..at].ends_with(char::is_whitespace);
        let value = &rest[at + key.len() + 2..];
        let end = value.find('"')?;
        if whole {
            return Some(unescape(&value[..end]));
        }
        rest = &value[end..];
    }
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&apos;", "'").replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    const REPORT: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<testsuites name="nextest-run" tests="3" failures="0" errors="0" time="9.5">
    <testsuite name="vpl-core::bvh" tests="2" disabled="0" errors="0" failures="0">
        <testcase name="a_quick_one" classname="vpl-core::bvh" timestamp="2026-12-04T19:00:00Z" time="0.012">
        </testcase>
        <testcase name="vec&lt;f32&gt; &amp; more" classname="vpl-core::bvh" timestamp="2026-12-04T19:00:00Z" time="7.25"/>
    </testsuite>
    <testsuite name="vpl-smc" tests="1">
        <testcase classname="vpl-smc" name="flux::tests::cells" time="2.5" subtime="1"></testcase>
    </testsuite>
</testsuites>"#;

    #[test]
    fn cases_are_read_with_their_times() {
        let cases = test_cases(REPORT);
        assert_eq!(cases.len(), 3);
        assert_eq!(cases[1], ("vpl-core::bvh".into(), "vec<f32> & more".into(), 7.25));
        // `subtime` is not `time`.
        assert_eq!(cases[2], ("vpl-smc".into(), "flux::tests::cells".into(), 2.5));
    }

    #[test]
    fn the_slowest_come_first() {
        let dir = std::env::temp_dir().join(format!("xtask-junit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("junit.xml");
        std::fs::write(&path, REPORT).unwrap();
        let table = slowest(&path, 2).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 3, "{table}");
        assert!(lines[0].contains("2 slowest of 3 tests"), "{table}");
        assert!(lines[1].contains("7.2 s") && lines[1].contains("vec<f32> & more"), "{table}");
        assert!(lines[2].contains("flux::tests::cells"), "{table}");
    }
}
