//! A picked VPL (its shadow map shown) and the path tracer's reference.

use super::*;

/// A picked VPL with its shadow map, and the path tracer's reference.
pub(super) struct Inspection {
    pub(super) reference_on: bool,
    pub(super) reference: Option<Reference>,
    pub(super) picked: Option<(usize, usize)>,
    pub(super) map: Option<(MapKey, MapPicture)>,
    pub(super) map_texture: Option<egui::TextureHandle>,
    pub(super) map_rect: Option<egui::Rect>,
}

impl State {
    /// The picked VPL, with the interleaving class that shades with it.
    pub(super) fn pick(&self) -> Option<Pick> {
        let (side, slot) = self.inspect.picked?;
        let s = self.picture.last.get(side)?;
        // The viewer's renderers shade interleaved (vpl_render's default).
        Some(Pick { side, slot, class: inspect::interleave_class(slot, s.out.vpls.len(), self.world.seed) })
    }

    /// Picks the visible VPL nearest to render pixel `(x, y)` (of the side
    /// the point lies in) within `radius` render pixels; none when no VPL is
    /// that near.
    pub(super) fn pick_at(&mut self, x: f32, y: f32, radius: f32) {
        let split = self.picture.composite.as_ref().and_then(|c| c.split_x);
        let k = match split {
            Some(sx) if x >= sx as f32 && self.picture.last.len() > 1 => 1,
            _ => 0,
        };
        let hosted = self.on_host();
        self.inspect.picked =
            hosted.get(k).and_then(|(s, g)| pick_vpl(SideFrame { gbuffer: g, ..side(s) }, x, y, radius)).map(|slot| (k, slot));
        self.report.status_line = Some(match self.inspect.picked {
            Some((k, slot)) => format!("picked VPL {slot} of {}", self.picture.last[k].spec.sampler),
            None => "no VPL near the click".into(),
        });
        self.refresh_map();
        self.picture.recompose = true;
    }

    /// Renders the picked VPL's shadow map when the VPL is new or moved.
    pub(super) fn refresh_map(&mut self) {
        let Some((k, slot)) = self.inspect.picked else {
            self.inspect.map = None;
            return;
        };
        let Some(v) = self.picture.last.get(k).and_then(|s| s.out.vpls.get(slot)).copied() else {
            self.inspect.map = None;
            return;
        };
        let key = (k, slot, [v.y.x, v.y.y, v.y.z, v.n.x, v.n.y, v.n.z]);
        if self.inspect.map.as_ref().is_some_and(|(m, _)| *m == key) {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.report.error_line = Some(e.to_string());
                return;
            }
        };
        let vpls = &self.picture.last[k].out.vpls;
        match inspect::shadow_map(&scene, vpls, slot, vpl_visibility::DEFAULT_RESOLUTION) {
            Ok(Some(m)) => {
                self.inspect.map = Some((key, m));
                self.inspect.map_texture = None;
            }
            Ok(None) => self.inspect.map = None,
            Err(e) => self.report.error_line = Some(format!("shadow map: {e}")),
        }
    }

    pub(super) fn set_reference(&mut self, on: bool) {
        self.inspect.reference_on = on;
        if !on {
            self.inspect.reference = None;
            self.picture.recompose = true;
        }
        self.changed(false);
    }
}
