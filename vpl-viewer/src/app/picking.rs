//! A picked VPL (its shadow map shown) and the path tracer's reference.

use super::*;

impl State {
    /// The picked VPL, with the interleaving class that shades with it.
    pub(super) fn pick(&self) -> Option<Pick> {
        let (side, slot) = self.picked?;
        let s = self.last.get(side)?;
        // The viewer's renderers shade interleaved (vpl_render's default).
        Some(Pick { side, slot, class: inspect::interleave_class(slot, s.out.vpls.len(), self.seed) })
    }

    /// Picks the visible VPL nearest to render pixel `(x, y)` (of the side
    /// the point lies in) within `radius` render pixels; none when no VPL is
    /// that near.
    pub(super) fn pick_at(&mut self, x: f32, y: f32, radius: f32) {
        let split = self.composite.as_ref().and_then(|c| c.split_x);
        let k = match split {
            Some(sx) if x >= sx as f32 && self.last.len() > 1 => 1,
            _ => 0,
        };
        let hosted = self.on_host();
        self.picked = hosted.get(k).and_then(|(s, g)| pick_vpl(SideFrame { gbuffer: g, ..side(s) }, x, y, radius)).map(|slot| (k, slot));
        self.status_line = Some(match self.picked {
            Some((k, slot)) => format!("picked VPL {slot} of {}", self.last[k].spec.sampler),
            None => "no VPL near the click".into(),
        });
        self.refresh_map();
        self.recompose = true;
    }

    /// Renders the picked VPL's shadow map when the VPL is new or moved.
    pub(super) fn refresh_map(&mut self) {
        let Some((k, slot)) = self.picked else {
            self.map = None;
            return;
        };
        let Some(v) = self.last.get(k).and_then(|s| s.out.vpls.get(slot)).copied() else {
            self.map = None;
            return;
        };
        let key = (k, slot, [v.y.x, v.y.y, v.y.z, v.n.x, v.n.y, v.n.z]);
        if self.map.as_ref().is_some_and(|(m, _)| *m == key) {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.error_line = Some(e.to_string());
                return;
            }
        };
        let vpls = &self.last[k].out.vpls;
        match inspect::shadow_map(&scene, vpls, slot, vpl_visibility::DEFAULT_RESOLUTION) {
            Ok(Some(m)) => {
                self.map = Some((key, m));
                self.map_texture = None;
            }
            Ok(None) => self.map = None,
            Err(e) => self.error_line = Some(format!("shadow map: {e}")),
        }
    }

    pub(super) fn set_reference(&mut self, on: bool) {
        self.reference_on = on;
        if !on {
            self.reference = None;
            self.recompose = true;
        }
        self.changed(false);
    }
}
