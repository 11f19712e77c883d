//! What the panel's plots show: each side's recent frames, and the
//! frames a side left on the host.

use super::*;

/// One side's recent frames, for the plots.
#[derive(Default)]
pub(super) struct History {
    /// (frame number, then the columns of [`History::COLUMNS`]).
    pub(super) rows: VecDeque<[f64; 9]>,
}

impl History {
    /// What the columns after the frame number hold.
    pub(super) const COLUMNS: [&'static str; 8] =
        ["total", "G-buffer", "sampling", "visibility", "shading", "direct", "VPLs moved", "Σ|ΔL|/ΣL"];

    pub(super) fn push(&mut self, s: &SideResult) {
        // A rebuilt side (another sampler, budget or mode) starts its plot afresh.
        if s.index == 0 {
            self.rows.clear();
        }
        let t = s.out.timings;
        self.rows.push_back([
            s.index as f64,
            t.total_ms,
            t.gbuffer_ms,
            t.sampling_ms,
            t.visibility_ms,
            t.shading_ms,
            t.direct_ms,
            s.out.moved as f64,
            s.change.unwrap_or(f64::NAN),
        ]);
        while self.rows.len() > HISTORY {
            self.rows.pop_front();
        }
    }

    pub(super) fn series(&self, column: usize) -> Vec<[f64; 2]> {
        self.rows.iter().filter(|r| r[column].is_finite()).map(|r| [r[0], r[column]]).collect()
    }
}

/// A side's image and G-buffer on the host: its frame's, or read back from
/// the device (on request: a click, a screenshot), `None` when the read
/// failed.
#[cfg(feature = "gpu")]
pub(super) fn host_frame(s: &SideResult) -> Option<(vpl_core::Image, vpl_core::GBuffer)> {
    let (d, gpu) = (s.device.as_ref()?, s.gpu.as_ref()?);
    Some((d.read_image(gpu.ctx()).ok()?, d.read_gbuffer(gpu.ctx()).ok()?))
}

pub(super) fn side(s: &SideResult) -> SideFrame<'_> {
    SideFrame { image: &s.out.image, gbuffer: &s.out.gbuffer, vpls: &s.out.vpls, camera: &s.camera }
}
