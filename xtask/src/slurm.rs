//! `cargo xtask reproduce --slurm`: Table 1 as a Slurm job array.
//!
//! `results/slurm/` receives two batch scripts and, once submitted, the
//! job ids:
//!
//! - `table1.sbatch`, an array of `--shards N` tasks: task i runs
//!   `vpl table1 … --shard i/N` into `results/table1/`. A unit a task
//!   finishes is a file there, and a task started again skips the units
//!   already written, so a task that fails (or is killed) requeues itself
//!   (`scontrol requeue`, at most [`MAX_REQUEUES`] times, then it fails for
//!   good) and a preempted one is requeued by Slurm (`--requeue`); either
//!   way it resumes from its units.
//! - `merge.sbatch`, which depends on the whole array (`afterok`) and
//!   runs `vpl merge results/table1`: the tables, equal bit for bit to
//!   those of an unsharded run.
//!
//! The tasks run the `vpl` binary built here (release), by its absolute
//! path: the compute nodes need the repository's folder (a shared file
//! system), not a toolchain. Where `sbatch` is on the PATH the scripts are
//! submitted and the ids written to `jobs.json`; `--dry-run` prints what
//! would be submitted instead. `--status` reports the units done per shard
//! (`vpl merge --status`), what `squeue` says of the jobs, and, when the
//! merge has written the tables, the README's Table 1 section.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Times a task requeues itself after a failure before it fails for good.
pub const MAX_REQUEUES: u32 = 3;

/// What the scripts ask of Slurm.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlurmSettings {
    /// Array tasks (shards).
    pub shards: u32,
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` of each task.
    pub time: Option<String>,
    /// `--cpus-per-task` (the tasks' `--threads`).
    pub cpus_per_task: u32,
    /// `--gpus-per-task` (0: none).
    pub gpus: u32,
    /// Print instead of submitting.
    pub dry_run: bool,
}

/// Quotes `s` for a POSIX shell.
fn quote(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./:=,+@%".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

fn header(out: &mut String, name: &str, s: &SlurmSettings, log: &str) {
    let _ = writeln!(out, "#!/bin/bash");
    let _ = writeln!(out, "#SBATCH --job-name={name}");
    let _ = writeln!(out, "#SBATCH --output={log}");
    let _ = writeln!(out, "#SBATCH --open-mode=append");
    let _ = writeln!(out, "#SBATCH --cpus-per-task={}", s.cpus_per_task.max(1));
    if let Some(p) = &s.partition {
        let _ = writeln!(out, "#SBATCH --partition={p}");
    }
    if let Some(t) = &s.time {
        let _ = writeln!(out, "#SBATCH --time={t}");
    }
}

/// The array's script: task i runs shard i/N of `table1_args` (the `vpl
/// table1` arguments but `--shard`, `--threads` and `--out`) into `out`.
pub fn array_script(root: &Path, vpl: &Path, table1_args: &[String], out: &Path, logs: &Path, s: &SlurmSettings) -> String {
    let mut sc = String::new();
    header(&mut sc, "vpl-table1", s, &format!("{}/table1-%A_%a.log", logs.display()));
    let _ = writeln!(sc, "#SBATCH --array=0-{}", s.shards.max(1) - 1);
    let _ = writeln!(sc, "#SBATCH --requeue");
    if s.gpus > 0 {
        let _ = writeln!(sc, "#SBATCH --gpus-per-task={}", s.gpus);
    }
    let args: Vec<String> = table1_args.iter().map(|a| quote(a)).collect();
    let _ = write!(
        sc,
        r#"# Written by `cargo xtask reproduce --slurm`: shard $SLURM_ARRAY_TASK_ID of {n} of Table 1.
# A task started again skips the units its earlier runs wrote.
set -uo pipefail
cd {root}
{vpl} table1 {args} --out {out} --shard "$SLURM_ARRAY_TASK_ID/{n}" --threads "${{SLURM_CPUS_PER_TASK:-1}}" --quiet
rc=$?
if [ "$rc" != 0 ] && [ "${{SLURM_RESTART_COUNT:-0}}" -lt {max} ]; then
  echo "vpl-table1: shard $SLURM_ARRAY_TASK_ID/{n} failed ($rc), requeued (restart ${{SLURM_RESTART_COUNT:-0}} of {max})" >&2
  scontrol requeue "${{SLURM_ARRAY_JOB_ID}}_${{SLURM_ARRAY_TASK_ID}}"
fi
exit "$rc"
"#,
        n = s.shards.max(1),
        root = quote(&root.display().to_string()),
        vpl = quote(&vpl.display().to_string()),
        args = args.join(" "),
        out = quote(&out.display().to_string()),
        max = MAX_REQUEUES,
    );
    sc
}

/// The merge job's script.
pub fn merge_script(root: &Path, vpl: &Path, out: &Path, logs: &Path, s: &SlurmSettings) -> String {
    let mut sc = String::new();
    let single = SlurmSettings { cpus_per_task: 1, ..s.clone() };
    header(&mut sc, "vpl-table1-merge", &single, &format!("{}/merge-%j.log", logs.display()));
    let _ = write!(
        sc,
        "# Written by `cargo xtask reproduce --slurm`: the tables of Table 1 once every shard is done.\nset -euo pipefail\ncd {}\n{} merge {}\n",
        quote(&root.display().to_string()),
        quote(&vpl.display().to_string()),
        quote(&out.display().to_string())
    );
    sc
}

/// Whether `program` is on the PATH.
pub fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(program).is_file()))
}

/// Submits `script` with `extra` arguments; the job id.
fn sbatch(script: &Path, extra: &[String]) -> Result<String, String> {
    let out = Command::new("sbatch").arg("--parsable").args(extra).arg(script).output().map_err(|e| format!("sbatch: {e}"))?;
    if !out.status.success() {
        return Err(format!("sbatch {}: {}", script.display(), String::from_utf8_lossy(&out.stderr).trim()));
    }
    // `--parsable` prints "id" or "id;cluster".
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(format!("sbatch {}: no job id in '{}'", script.display(), text.trim()));
    }
    Ok(id)
}

/// Writes the scripts into `dir` (`results/slurm`) and submits them, or
/// prints them under `--dry-run` or where `sbatch` is not on the PATH.
pub fn submit(root: &Path, vpl: &Path, table1_args: &[String], out: &Path, dir: &Path, s: &SlurmSettings) -> Result<(), String> {
    if s.shards == 0 {
        return Err("--shards must be at least 1".into());
    }
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("cannot create {}: {e}", logs.display()))?;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let array = dir.join("table1.sbatch");
    let merge = dir.join("merge.sbatch");
    crate::write_atomic(&array, &array_script(root, vpl, table1_args, out, &logs, s))?;
    crate::write_atomic(&merge, &merge_script(root, vpl, out, &logs, s))?;
    if s.dry_run || !on_path("sbatch") {
        let why = if s.dry_run { "--dry-run" } else { "sbatch is not on the PATH" };
        eprintln!("xtask: {why}: not submitted; would run:");
        println!("sbatch --parsable {}", array.display());
        println!("sbatch --parsable --dependency=afterok:<array job> {}", merge.display());
        return Ok(());
    }
    let array_id = sbatch(&array, &[])?;
    let merge_id = sbatch(&merge, &[format!("--dependency=afterok:{array_id}")])?;
    let jobs = serde_json::json!({
        "array": array_id,
        "merge": merge_id,
        "shards": s.shards,
        "out": out,
        "args": table1_args,
    });
    let text = serde_json::to_string_pretty(&jobs).map_err(|e| e.to_string())?;
    crate::write_atomic(&dir.join("jobs.json"), &text)?;
    eprintln!("xtask: submitted Table 1 as array job {array_id} ({} shards), merge job {merge_id} after it", s.shards);
    eprintln!("xtask: watch it with `cargo xtask reproduce --slurm --status`");
    Ok(())
}

/// The submitted run of `dir`: (array id, merge id, shards, output folder).
pub fn jobs(dir: &Path) -> Result<(String, String, u32, PathBuf), String> {
    let path = dir.join("jobs.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e} (nothing submitted yet?)", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let s = |k: &str| v[k].as_str().map(str::to_string).ok_or_else(|| format!("{}: no '{k}'", path.display()));
    let shards = v["shards"].as_u64().and_then(|n| u32::try_from(n).ok()).ok_or_else(|| format!("{}: no 'shards'", path.display()))?;
    Ok((s("array")?, s("merge")?, shards, PathBuf::from(s("out")?)))
}

/// What `squeue` says of `ids` (empty where it is not on the PATH or
/// knows none of them: finished jobs leave the queue).
pub fn queue(ids: &[&str]) -> String {
    if !on_path("squeue") {
        return String::new();
    }
    let out = Command::new("squeue").args(["--noheader", "--format=%i %j %T %r", "--jobs"]).arg(ids.join(",")).output();
    match out {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).into_owned(),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_array_runs_one_shard_a_task_and_requeues_a_failed_one() {
        let s = SlurmSettings {
            shards: 4,
            partition: Some("gpu".into()),
            time: Some("02:00:00".into()),
            cpus_per_task: 8,
            gpus: 1,
            dry_run: true,
        };
        let args: Vec<String> = ["--profile", "full", "--methods", "smc,ir", "--scene", "it's"].map(String::from).to_vec();
        let sc = array_script(
            Path::new("/repo"),
            Path::new("/repo/target/release/vpl"),
            &args,
            Path::new("/repo/results/table1"),
            Path::new("/repo/results/slurm/logs"),
            &s,
        );
        for line in [
            "#SBATCH --array=0-3",
            "#SBATCH --requeue",
            "#SBATCH --partition=gpu",
            "#SBATCH --time=02:00:00",
            "#SBATCH --cpus-per-task=8",
            "#SBATCH --gpus-per-task=1",
            "/repo/target/release/vpl table1 --profile full --methods smc,ir --scene 'it'\\''s' --out /repo/results/table1 --shard \"$SLURM_ARRAY_TASK_ID/4\"",
            "scontrol requeue",
        ] {
            assert!(sc.contains(line), "missing {line:?} in\n{sc}");
        }
        let m =
            merge_script(Path::new("/repo"), Path::new("/repo/target/release/vpl"), Path::new("/repo/results/table1"), Path::new("/l"), &s);
        assert!(m.contains("/repo/target/release/vpl merge /repo/results/table1") && !m.contains("--array"), "{m}");
    }
}
