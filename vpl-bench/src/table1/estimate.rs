//! What the full profile of Table 1 (whole sequences, the paper's truth
//! samples, its seeds) would take for a run's methods and sequences on
//! this machine, from the costs the run measured: each method unit's wall time plus the frames the
//! full sequence adds at that unit's median per-frame time (the first
//! frame, which builds everything, is in the unit's time once), and the
//! ground truth's time per frame: its sampling scaled by the full
//! profile's samples, its set-up (the scene, a device's upload) not.

use super::{MethodUnit, Table1Spec};
use serde::{Deserialize, Serialize};

/// The estimate, in seconds of wall time on the machine and thread count
/// of the run it was made from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FullEstimate {
    /// Method runs (every seed of every method on every sequence).
    pub method_seconds: f64,
    /// Ground truth; `None` where the run's truth units record no time
    /// (units of older versions).
    pub truth_seconds: Option<f64>,
    /// Sequences of the run that the full profile also has (the others are
    /// not counted).
    pub rows: Vec<String>,
    /// The adapter that path-traced the run's truth (`None`: the CPU).
    #[serde(default)]
    pub truth_device: Option<String>,
}

impl FullEstimate {
    /// Method runs and ground truth together (method runs alone without a
    /// truth time).
    pub fn total_seconds(&self) -> f64 {
        self.method_seconds + self.truth_seconds.unwrap_or(0.0)
    }
}

/// Per row of `spec`: the seconds its truth units took, as (set-up,
/// sampling) (`None` if any recorded none).
pub(super) type TruthSeconds = Vec<Option<(f64, f64)>>;

/// The estimate of `full` from a run of `spec` with method units `runs` and
/// truth times `truth` (per row of `spec`); `None` where no row of the run
/// is in `full`.
pub fn estimate(spec: &Table1Spec, runs: &[MethodUnit], truth: &TruthSeconds, full: &Table1Spec) -> Option<FullEstimate> {
    let mut method_seconds = 0.0;
    let mut truth_seconds = Some(0.0);
    let mut rows = Vec::new();
    for (run, t) in spec.rows.iter().zip(truth) {
        let Some(f) = full.rows.iter().find(|f| f.id == run.id) else { continue };
        let (quick, whole) = (run.end.saturating_sub(run.start) as f64, f.end.saturating_sub(f.start) as f64);
        if quick == 0.0 {
            continue;
        }
        rows.push(run.id.clone());
        let units: Vec<&MethodUnit> = runs.iter().filter(|u| u.row == run.id).collect();
        let per_unit: f64 = units.iter().map(|u| u.seconds + (whole - quick).max(0.0) * median_frame_seconds(u)).sum();
        // The full profile's seeds: a method's units scale with their number.
        method_seconds += per_unit * full.seeds as f64 / spec.seeds.max(1) as f64;
        truth_seconds = match (truth_seconds, t) {
            (Some(sum), Some((setup, sampling))) => {
                Some(sum + (setup + sampling * full.truth_spp as f64 / spec.truth_spp.max(1) as f64) / quick * whole)
            }
            _ => None,
        };
    }
    (!rows.is_empty()).then_some(FullEstimate { method_seconds, truth_seconds, rows, truth_device: None })
}

/// The median of a unit's per-frame total times after its first frame, in
/// seconds (its only frame's when it has one).
fn median_frame_seconds(u: &MethodUnit) -> f64 {
    let mut ms: Vec<f64> = u.ms.iter().skip(1).map(|m| m[4]).collect();
    if ms.is_empty() {
        ms = u.ms.iter().map(|m| m[4]).collect();
    }
    if ms.is_empty() {
        return 0.0;
    }
    ms.sort_by(f64::total_cmp);
    ms[ms.len() / 2] / 1e3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table1::RowRun;

    fn unit(row: &str, seconds: f64, ms: &[f64]) -> MethodUnit {
        MethodUnit {
            settings: None,
            row: row.into(),
            method: "ir".into(),
            seed: 0,
            frames: (0..ms.len() as u32).collect(),
            tracked: Vec::new(),
            moved: Vec::new(),
            ms: ms.iter().map(|&t| [0.0, 0.0, 0.0, 0.0, t]).collect(),
            seconds,
        }
    }

    /// Two units of 8 frames (10 s each; 100 ms a frame after the first) on
    /// a 108-frame sequence: each adds 100 frames × 0.1 s; truth 4 s of
    /// sampling for 8 frames at 1,000 samples scales to 108 frames at
    /// 10,000, and its 0.8 s of set-up to 108 frames alone.
    #[test]
    fn the_estimate_adds_the_missing_frames_at_the_measured_cost() {
        let mut spec = Table1Spec::quick();
        spec.rows = vec![RowRun { id: "office".into(), start: 0, end: 8 }];
        spec.methods = vec!["ir".into()];
        spec.seeds = 2;
        spec.truth_spp = 1000;
        let mut full = spec.clone();
        full.rows = vec![RowRun { id: "office".into(), start: 0, end: 108 }, RowRun { id: "maze".into(), start: 0, end: 50 }];
        full.truth_spp = 10_000;
        let ms = [5000.0, 100.0, 90.0, 110.0, 100.0, 100.0, 100.0, 100.0];
        let runs = vec![unit("office", 10.0, &ms), unit("office", 10.0, &ms)];
        let e = estimate(&spec, &runs, &vec![Some((0.8, 4.0))], &full).unwrap();
        assert!((e.method_seconds - 2.0 * (10.0 + 100.0 * 0.1)).abs() < 1e-9, "{e:?}");
        assert!((e.truth_seconds.unwrap() - (0.8 + 4.0 * 10.0) / 8.0 * 108.0).abs() < 1e-9, "{e:?}");
        assert_eq!(e.rows, vec!["office".to_string()]);
        assert_eq!(estimate(&spec, &runs, &vec![None], &full).unwrap().truth_seconds, None);
        full.rows.remove(0);
        assert_eq!(estimate(&spec, &runs, &vec![Some((0.8, 4.0))], &full), None);
    }
}
