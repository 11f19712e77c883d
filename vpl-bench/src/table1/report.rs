//! Table 1's files: `table1.md`, `table1.csv`, `table1.json`, the Fig. 7
//! plots and their data, and `runs.csv` (per-unit timings, which vary from
//! run to run and so stay out of the other files).

use super::rows::{self, PAPER_METHODS};
use super::stats::{Interval, REPLICATES};
use super::{MethodUnit, RowResult, Table1Error, Table1Results};
use crate::plot::{Chart, Series, line_chart_png, method_color};
use crate::stages::median;
use std::fmt::Write as _;
use std::path::Path;

/// The sequences Fig. 7 plots, as the paper: Citadel with the moving sun, Soda Hall, Maze.
pub const FIG7_ROWS: [&str; 3] = ["courtyard-sun", "office", "maze"];

/// The name a method goes by in tables.
pub fn display_name(method: &str) -> String {
    match method {
        "ir" => "IR".into(),
        "rr" => "RR".into(),
        "mir-resample" => "MIR".into(),
        "mir" => "MIR (MH)".into(),
        "tcas" => "TCAS".into(),
        "smc" => "SMC".into(),
        "smc-knn" => "SMC (kNN flux)".into(),
        // A registry name with settings: `smc:flux=knn` is "SMC (flux=knn)".
        m => match m.split_once(':') {
            Some((name, settings)) => format!("{} ({})", display_name(name), settings.replace(':', ", ")),
            None => m.to_string(),
        },
    }
}

fn paper_index(method: &str) -> Option<usize> {
    PAPER_METHODS.iter().position(|m| *m == method)
}

/// Our values of one metric for a row with their 95 % intervals, bold where smallest.
fn metric_cells(row: &RowResult, get: impl Fn(&super::MethodResult) -> (f64, Interval)) -> String {
    let vals: Vec<(f64, Interval)> = row.methods.iter().map(&get).collect();
    let best = vals.iter().map(|v| v.0).fold(f64::INFINITY, f64::min);
    vals.iter()
        .map(|(v, ci)| {
            let value = if *v == best { format!("**{v:.4}**") } else { format!("{v:.4}") };
            format!(" {value} [{:.4}, {:.4}] |", ci.lo, ci.hi)
        })
        .collect()
}

fn paper_cells(row: &RowResult, methods: &[String], vals: impl Fn(&rows::PaperRow) -> [f64; 4]) -> String {
    let p = rows::row(&row.id).expect("known row").paper;
    let v = vals(&p);
    let shown: Vec<Option<f64>> = methods.iter().map(|m| paper_index(m).map(|i| v[i])).collect();
    let best = shown.iter().flatten().copied().fold(f64::INFINITY, f64::min);
    shown
        .iter()
        .map(|s| match s {
            Some(x) if *x == best => format!(" **{x:.4}** |"),
            Some(x) => format!(" {x:.4} |"),
            None => " – |".into(),
        })
        .collect()
}

/// A table of one cell per sequence and method, then a blank line.
fn method_table(md: &mut String, names: &[String], r: &Table1Results, cell: impl Fn(&super::MethodResult) -> String) {
    md.push_str("| sequence |");
    for n in names {
        let _ = write!(md, " {n} |");
    }
    md.push_str("\n| --- |");
    md.push_str(&" ---: |".repeat(names.len()));
    md.push('\n');
    for row in &r.rows {
        let _ = write!(md, "| `{}` |", row.id);
        for m in &row.methods {
            let _ = write!(md, " {} |", cell(m));
        }
        md.push('\n');
    }
    md.push('\n');
}

/// `table1.md`.
pub fn markdown(r: &Table1Results) -> String {
    let s = &r.spec;
    let names: Vec<String> = s.methods.iter().map(|m| display_name(m)).collect();
    let mut md = String::from("# Table 1: error and temporal instability of the VPL samplers\n\n");
    let _ = writeln!(
        md,
        "Hedman et al. 2017, §5.2, redone on the built-in scenes and on real geometry (`sponza`: Dabrovic Sponza with a \
         point light moving along the nave; `munich`: Munich city blocks under a moving sun; scene files in `scenes/`). Eight tracked pixels per sequence; indirect light only, \
         luminance after Reinhard's operator L/(1+L); ground truth from the path tracer ({} samples per pixel and frame, \
         rays through the pixel centre, on the run's backend); every method with the same VPL budget, {}² paraboloid shadow maps, 4×4 interleaved \
         shading, the cross-bilateral filter and the clamp G_max = I / A_view of each frame's view; no temporal reprojection; max depth {} (three \
         indirect bounces). |E′| is the mean absolute change of the error from one frame to the next (Δt = one frame at 30 fps). \
         Profile `{}`, {}×{} pixels, {} backend. MIR is the resampling stand-in the paper used (256 path-tracer paths per VPL); SMC is the toolkit's default \
         (each VPL's flux is its Voronoi cell's light as the VPL shows it to the camera), SMC (kNN flux) the paper's flux (eq. 5 and 7). \
         Every method ran {} times (seeds {}..{}); values are over all runs, frames and tracked pixels, with 95 % confidence \
         intervals in brackets: a two-way percentile bootstrap ({} replicates) that resamples seeds and tracked pixels and keeps \
         each pixel's series of frames whole (frames are correlated and |E′| needs consecutive ones). \
         Smallest value in bold; the paper's values (its Table 1) on the right.\n",
        s.truth_spp,
        s.shadow_map_res,
        s.max_depth,
        s.profile,
        s.size.0,
        s.size.1,
        match s.backend {
            crate::pipeline::BackendKind::Cpu => "CPU",
            crate::pipeline::BackendKind::Gpu => "GPU",
        },
        s.seeds,
        s.seed,
        s.seed + s.seeds as u64 - 1,
        REPLICATES
    );
    let skipped = super::skipped_rows();
    if !skipped.is_empty() {
        let list: Vec<String> = skipped.iter().map(|(id, why)| format!("`{id}` ({why})")).collect();
        let _ = writeln!(md, "Not run on this machine: {}.\n", list.join("; "));
    }
    for (title, get, paper) in [
        (
            "Average |E|",
            (|m: &super::MethodResult| (m.error.e, m.intervals.e)) as fn(&super::MethodResult) -> (f64, Interval),
            (|p: &rows::PaperRow| p.e) as fn(&rows::PaperRow) -> [f64; 4],
        ),
        ("Average |E′|", |m| (m.error.e_prime, m.intervals.e_prime), |p| p.e_prime),
    ] {
        let _ = writeln!(md, "## {title}\n");
        let mut head = String::from("| sequence | stands in for | lights | VPLs | frames |");
        let mut rule = String::from("| --- | --- | --- | --- | --- |");
        for n in &names {
            let _ = write!(head, " {n} |");
            rule.push_str(" ---: |");
        }
        head.push_str(" truth s.e. |");
        rule.push_str(" ---: |");
        for n in &names {
            let _ = write!(head, " paper {n} |");
            rule.push_str(" ---: |");
        }
        let _ = writeln!(md, "{head}\n{rule}");
        for row in &r.rows {
            let p = rows::row(&row.id).expect("known row").paper;
            let _ = writeln!(
                md,
                "| `{}` | {} | {} | {} | {}..{} |{} {:.4} |{}",
                row.id,
                p.scene,
                p.lights,
                row.vpls,
                row.frames.0,
                row.frames.1,
                metric_cells(row, get),
                row.truth_stderr,
                paper_cells(row, &s.methods, paper)
            );
        }
        md.push('\n');
    }
    md.push_str(
        "## Mean signed error\n\nThe mean of estimate − truth over runs, frames and pixels, with its 95 % interval: noise averages \
         out here, a bias does not.\n\n",
    );
    method_table(&mut md, &names, r, |m| format!("{:+.4} [{:+.4}, {:+.4}]", m.error.bias, m.intervals.bias.lo, m.intervals.bias.hi));
    if s.seeds >= 2 {
        md.push_str(
            "## How much of the error is bias and how much noise\n\nThe mean squared error of estimate − truth split per frame and \
             pixel into the variance across seeds (noise) and the square of the seeds' mean error less its noise (bias²); the cells \
             give the noise's share of the mean squared error, then √bias² and √noise. The ground truth's own error is the same \
             for every seed and so counts as bias here (its size is the truth s.e. column above).\n\n",
        );
        method_table(&mut md, &names, r, |m| match m.split {
            Some(sp) => format!("{:.0} % noise ({:.4} / {:.4})", 100.0 * sp.noise_share(), sp.bias2.max(0.0).sqrt(), sp.noise.sqrt()),
            None => "–".into(),
        });
    }
    md.push_str(
        "## The target: SMC lowest |E′| in every sequence, |E| no worse than MIR's\n\nDifferences SMC − other with their 95 % \
         intervals from the same bootstrap draws (paired: the same seeds and pixels for both methods): significant when the \
         interval excludes zero. The others are every method but SMC's own variants (SMC (kNN flux) is SMC with the paper's \
         flux, eq. 5 and 7, in place of the default cell flux).\n\n| sequence | SMC \\|E′\\| | lowest other \\|E′\\| | SMC − it | SMC's \\|E′\\| | SMC \\|E\\| | MIR \\|E\\| | SMC − MIR | SMC's \\|E\\| against MIR's |\n\
         | --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | --- |\n",
    );
    for row in &r.rows {
        let find = |m: &str| row.methods.iter().find(|x| x.method == m);
        let Some(smc) = find("smc") else { continue };
        let versus = |m: &str| row.comparisons.iter().find(|c| c.method == m).map(|c| c.smc_minus);
        let other = row
            .methods
            .iter()
            .filter(|m| m.method != "smc" && !super::is_smc_variant(&m.method))
            .min_by(|a, b| a.error.e_prime.total_cmp(&b.error.e_prime));
        // A run of SMC's variants alone has no other method to compare with.
        let lowest = other.map_or("–".to_string(), |o| format!("{:.4} ({})", o.error.e_prime, display_name(&o.method)));
        let d_prime = other.and_then(|o| versus(&o.method)).map(|d| d.e_prime);
        let mir = find("mir-resample").map(|m| m.error.e);
        let d_e = versus("mir-resample").map(|d| d.e);
        let ci = |d: Option<Interval>| d.map_or("–".to_string(), |d| format!("[{:+.4}, {:+.4}]", d.lo, d.hi));
        let _ = writeln!(
            md,
            "| `{}` | {:.4} | {lowest} | {} | {} | {:.4} | {} | {} | {} |",
            row.id,
            smc.error.e_prime,
            ci(d_prime),
            d_prime.map_or("–", |d| d.sign().words()),
            smc.error.e,
            mir.map_or("–".into(), |v| format!("{v:.4}")),
            ci(d_e),
            d_e.map_or("–", |d| d.sign().words()),
        );
    }
    md.push_str("\n## Tracked pixels\n\n");
    for row in &r.rows {
        let _ = writeln!(
            md,
            "- `{}`: {}",
            row.id,
            row.pixels.iter().enumerate().map(|(i, ((x, y), l))| format!("{i} ({x}, {y}) {l}")).collect::<Vec<_>>().join("; ")
        );
    }
    md
}

/// `table1.csv`: one line per sequence and method.
pub fn csv(r: &Table1Results) -> String {
    let mut s = String::from(
        "sequence,scene,vpls,frame_start,frame_end,method,seeds,e,e_lo,e_hi,e_prime,e_prime_lo,e_prime_hi,bias,bias_lo,bias_hi,noise_share,\
         e_per_seed,count,count_prime,truth_stderr,median_moved,paper_e,paper_e_prime\n",
    );
    for row in &r.rows {
        let p = rows::row(&row.id).expect("known row").paper;
        for m in &row.methods {
            let (pe, pp) =
                paper_index(&m.method).map_or((String::new(), String::new()), |i| (p.e[i].to_string(), p.e_prime[i].to_string()));
            let ci = m.intervals;
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{},{},{},{},{:.6},{},{pe},{pp}",
                row.id,
                row.scene,
                row.vpls,
                row.frames.0,
                row.frames.1,
                m.method,
                m.luminance.len(),
                m.error.e,
                ci.e.lo,
                ci.e.hi,
                m.error.e_prime,
                ci.e_prime.lo,
                ci.e_prime.hi,
                m.error.bias,
                ci.bias.lo,
                ci.bias.hi,
                m.split.map_or(String::new(), |sp| format!("{:.4}", sp.noise_share())),
                m.e_per_seed.iter().map(|e| format!("{e:.6}")).collect::<Vec<_>>().join(";"),
                m.error.count,
                m.error.count_prime,
                row.truth_stderr,
                m.median_moved
            );
        }
    }
    s
}

/// `runs.csv`: median milliseconds per stage and wall time of each unit.
pub fn runs_csv(runs: &[MethodUnit]) -> String {
    let mut s = String::from("sequence,method,seed,frames,seconds,gbuffer_ms,sampling_ms,visibility_ms,shading_ms,total_ms\n");
    for u in runs {
        let med = |i: usize| median(u.ms.iter().skip(1).map(|m| m[i]).collect());
        let _ = writeln!(
            s,
            "{},{},{},{},{:.1},{:.2},{:.2},{:.2},{:.2},{:.2}",
            u.row,
            u.method,
            u.seed,
            u.frames.len(),
            u.seconds,
            med(0),
            med(1),
            med(2),
            med(3),
            med(4)
        );
    }
    s
}

/// Fig. 7: the tracked pixel's luminance over time, per method against
/// ground truth, for the rows of [`FIG7_ROWS`] in the run: one line per
/// seed in the method's colour, so the spread across runs shows.
/// Files made in memory: (path, bytes).
type Files = Vec<(std::path::PathBuf, Vec<u8>)>;

fn fig7(dir: &Path, r: &Table1Results) -> Result<(String, Files), Table1Error> {
    let mut pngs = Vec::new();
    let mut data = String::from("sequence,pixel,x,y,frame,time,method,seed,luminance\n");
    for row in r.rows.iter().filter(|row| FIG7_ROWS.contains(&row.id.as_str())) {
        let def = rows::row(&row.id).expect("known row");
        let k = def.fig7_pixel;
        let t0 = row.frames.0;
        let time = |i: usize| (t0 as usize + i) as f64 / 30.0;
        let mut series = vec![Series {
            label: "ground truth".into(),
            points: row.truth.iter().enumerate().map(|(i, f)| (time(i), f[k])).collect(),
            color: method_color("truth"),
            bold: true,
            markers: false,
        }];
        let ((x, y), label) = &row.pixels[k];
        for (i, (t, l)) in series[0].points.iter().enumerate() {
            let _ = writeln!(data, "{},{k},{x},{y},{},{t:.4},ground truth,,{l:.6}", row.id, t0 as usize + i);
        }
        for m in &row.methods {
            for (seed, lum) in m.luminance.iter().enumerate() {
                let points: Vec<(f64, f64)> = lum.iter().enumerate().map(|(i, f)| (time(i), f[k])).collect();
                let name = display_name(&m.method);
                for (i, (t, l)) in points.iter().enumerate() {
                    let _ = writeln!(data, "{},{k},{x},{y},{},{t:.4},{name},{},{l:.6}", row.id, t0 as usize + i, r.spec.seed + seed as u64);
                }
                // The legend names a method once.
                let label = if seed == 0 { name } else { String::new() };
                series.push(Series { label, points, color: method_color(&m.method), bold: false, markers: row.truth.len() < 40 });
            }
        }
        let runs = if r.spec.seeds > 1 { format!(", {} seeds each", r.spec.seeds) } else { String::new() };
        let title = format!("{} ({} VPLs{runs}), pixel {k} ({x}, {y}): {label}", row.id, row.vpls);
        let chart = Chart { title: &title, x_label: "seconds", y_label: "luminance (Reinhard)", log: (false, false), size: (960, 420) };
        let path = dir.join(format!("fig7_{}.png", row.id));
        let png = line_chart_png(&path.display().to_string(), &chart, &series)?;
        pngs.push((path, png));
    }
    Ok((data, pngs))
}

/// The estimate's line: "… h for the full profile (… method runs, …
/// ground truth)".
pub fn estimate_line(e: &super::estimate::FullEstimate) -> String {
    let h = |s: f64| s / 3600.0;
    match e.truth_seconds {
        Some(t) => format!(
            "{:.1} h for the full profile of these methods on {} ({:.1} h method runs, {:.1} h ground truth{})",
            h(e.total_seconds()),
            e.rows.join(", "),
            h(e.method_seconds),
            h(t),
            e.truth_device.as_ref().map_or(String::new(), |d| format!(" on {d}"))
        ),
        None => format!(
            "{:.1} h of method runs for the full profile of these methods on {} (ground truth not timed)",
            h(e.method_seconds),
            e.rows.join(", ")
        ),
    }
}

/// `cost.md`: the wall times of the run and the estimate of the full profile.
fn cost_md(runs: &[MethodUnit], cost: Option<&super::estimate::FullEstimate>) -> String {
    let mut md = String::from(
        "# Cost of the Table 1 run

",
    );
    let seconds: f64 = runs.iter().map(|u| u.seconds).sum();
    let _ = writeln!(
        md,
        "Method units: {seconds:.0} s of wall time in all (per unit and stage: `runs.csv`).
"
    );
    match cost {
        Some(e) => {
            let _ = writeln!(
                md,
                "From this run's measured costs (each unit's time plus the frames a whole sequence adds at its median \
                 time per frame; ground truth per frame scaled to the paper's samples), on the same machine and threads: {}.",
                estimate_line(e)
            );
        }
        None => md.push_str("No estimate of the full profile: its sequences could not be read, or share none with this run.\n"),
    }
    md
}

/// Writes every Table 1 file into `dir`, all or none: every file is made
/// and staged first, then all are renamed into place
/// ([`vpl_core::image::Staging`]), so a merge that fails leaves the
/// folder's earlier results as they were.
pub fn write(dir: &Path, r: &Table1Results, runs: &[MethodUnit], cost: Option<&super::estimate::FullEstimate>) -> Result<(), Table1Error> {
    let json = serde_json::to_string_pretty(r).map_err(|e| Table1Error::Invalid(e.to_string()))?;
    let (data, pngs) = fig7(dir, r)?;
    let mut files: Files = vec![
        (dir.join("table1.md"), markdown(r).into_bytes()),
        (dir.join("table1.csv"), csv(r).into_bytes()),
        (dir.join("table1.json"), json.into_bytes()),
        (dir.join("runs.csv"), runs_csv(runs).into_bytes()),
        (dir.join("cost.md"), cost_md(runs, cost).into_bytes()),
        (dir.join("fig7.csv"), data.into_bytes()),
    ];
    files.extend(pngs);
    let mut staging = vpl_core::image::Staging::new();
    for (path, bytes) in &files {
        staging.stage(path, bytes)?;
    }
    staging.commit()?;
    Ok(())
}
