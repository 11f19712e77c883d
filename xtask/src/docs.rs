//! `docs/reproduction.md`: the reproduction as committed, written from a
//! `results/` folder (`cargo xtask reproduce --docs`, or `cargo xtask docs`
//! for the folder as it is).
//!
//! The page is `results/README.md` with the commit, the machine and the
//! date on top. Its links are made to work from `docs/`: the plots
//! (PNG files of at most [`MAX_PNG_BYTES`] from the jobs whose pictures are
//! charts) are copied into `docs/reproduction/`; every other link (EXR
//! images, renders, data files, which stay in `results/`) becomes its
//! path as text.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The folders of `results/` whose PNG files are plots worth committing.
const PLOT_FOLDERS: [&str; 5] = ["table1/", "georgiev/", "figures/", "progressive/", "manylights/"];

/// The largest PNG copied into `docs/reproduction/` (a chart is 20–80 KB).
pub const MAX_PNG_BYTES: u64 = 200 * 1024;

/// Writes `docs/reproduction.md` and `docs/reproduction/` from `results`.
pub fn write(root: &Path, results: &Path) -> Result<(), String> {
    let readme = std::fs::read_to_string(results.join("README.md"))
        .map_err(|e| format!("{}: {e} (run `cargo xtask reproduce` first)", results.join("README.md").display()))?;
    let docs = root.join("docs");
    let assets = docs.join("reproduction");
    // The new plots go to a staging folder that replaces the old one whole,
    // so that no plot of an earlier run stays behind.
    let staging = docs.join(".reproduction.tmp");
    let _ = std::fs::remove_dir_all(&staging);
    std::fs::create_dir_all(&staging).map_err(|e| format!("cannot create {}: {e}", staging.display()))?;
    let body = relink(&readme, |target| {
        let keep = PLOT_FOLDERS.iter().any(|f| target.starts_with(f))
            && target.ends_with(".png")
            && !target.contains("..")
            && std::fs::metadata(results.join(target)).is_ok_and(|m| m.is_file() && m.len() <= MAX_PNG_BYTES);
        if !keep {
            return None;
        }
        let name = target.replace('/', "_");
        std::fs::copy(results.join(target), staging.join(&name)).ok()?;
        Some(format!("reproduction/{name}"))
    });
    let page = format!("{}{}", header(root), body.trim_start_matches("# Results\n\n"));
    let _ = std::fs::remove_dir_all(&assets);
    std::fs::rename(&staging, &assets).map_err(|e| format!("cannot write {}: {e}", assets.display()))?;
    crate::write_atomic(&docs.join("reproduction.md"), &page)?;
    eprintln!("xtask: wrote docs/reproduction.md and {} plots in docs/reproduction/", count_files(&assets));
    Ok(())
}

fn count_files(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |d| d.count())
}

/// The page's title and where it was made: commit, machine, date.
fn header(root: &Path) -> String {
    let git = |args: &[&str]| {
        Command::new("git")
            .current_dir(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = git(&["rev-parse", "--short=12", "HEAD"]).unwrap_or_else(|| "unknown".into());
    // Changes to tracked files other than this page and its plots make the
    // run not that of the commit: said on the page.
    let dirty = git(&["status", "--porcelain", "--untracked-files=no", "--", ".", ":!docs/reproduction.md", ":!docs/reproduction"])
        .is_some_and(|s| !s.is_empty());
    let date = Command::new("date")
        .args(["-u", "+%Y-%m-%d"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    format!(
        "# The reproduction\n\nWhat `cargo xtask reproduce` wrote, run on commit `{commit}`{} on {} ({date}). \
         `cargo xtask reproduce --docs` writes this page and the plots beside it (`docs/reproduction/`) from the `results/` \
         folder of the run; the renders, EXR images and data files stay in `results/` and are named here by their paths. \
         The wall time of each job is at the end.\n\n",
        if dirty { " with uncommitted changes" } else { "" },
        machine()
    )
}

/// The processor, its hardware threads and the memory, from `/proc`.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| t.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split_once(':')).map(|(_, v)| v.trim().to_string()))
        .unwrap_or_else(|| "an unknown processor".into());
    let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| t.lines().find(|l| l.starts_with("MemTotal:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok()))
        .map_or(String::new(), |kb| format!(", {:.0} GiB of memory", kb / (1024.0 * 1024.0)));
    format!("{cpu}, {threads} hardware threads{mem}")
}

/// `md` with each link `[text](target)` or image `![text](target)` whose
/// target is relative handed to `copy`: where it returns the new target
/// the link points there, else the link becomes its target as code
/// (`results/target`). Absolute URLs and anchors are kept.
pub fn relink(md: &str, mut copy: impl FnMut(&str) -> Option<String>) -> String {
    let mut out = String::with_capacity(md.len());
    let mut rest = md;
    while let Some(mid) = rest.find("](") {
        let (before, after) = rest.split_at(mid);
        let Some(close) = after[2..].find(')') else { break };
        let target = &after[2..2 + close];
        let Some(open) = before.rfind('[') else {
            out.push_str(&rest[..mid + 2]);
            rest = &rest[mid + 2..];
            continue;
        };
        let image = open > 0 && before.as_bytes()[open - 1] == b'!';
        let start = if image { open - 1 } else { open };
        let text = &before[open + 1..];
        let external = target.contains("://") || target.starts_with('#') || target.starts_with('/') || target.contains(' ');
        out.push_str(&before[..start]);
        if external {
            out.push_str(&rest[start..mid + 3 + close]);
        } else {
            match copy(target) {
                Some(new) => {
                    out.push_str(if image { "![" } else { "[" });
                    out.push_str(text);
                    out.push_str("](");
                    out.push_str(&new);
                    out.push(')');
                }
                None if image || text.is_empty() => out.push_str(&format!("`results/{target}`")),
                None => out.push_str(&format!("{text} (`results/{target}`)")),
            }
        }
        rest = &after[3 + close..];
    }
    out.push_str(rest);
    out
}

/// `results/` of the repository.
pub fn results(root: &Path) -> PathBuf {
    root.join("results")
}

#[cfg(test)]
mod tests {
    use super::relink;

    #[test]
    fn plots_are_relinked_and_other_links_become_paths() {
        let md = "A ![Fig. 7](table1/fig7_office.png) and [exr](references/x.exr) ![](scenes/a.png), \
                  [site](https://example.org) [t](#top); `table1/`.";
        let out = relink(md, |t| t.starts_with("table1/").then(|| format!("reproduction/{}", t.replace('/', "_"))));
        assert_eq!(
            out,
            "A ![Fig. 7](reproduction/table1_fig7_office.png) and exr (`results/references/x.exr`) `results/scenes/a.png`, \
             [site](https://example.org) [t](#top); `table1/`."
        );
    }

    #[test]
    fn text_without_links_is_unchanged() {
        let md = "| a | b |\n| --- | --- |\n[not a link] (x) and f(x)\n";
        assert_eq!(relink(md, |_| None), md);
    }
}
