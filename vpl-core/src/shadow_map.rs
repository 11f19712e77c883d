//! A VPL's paraboloid shadow map as shaders read it: the texels' depths and
//! the map's frame, borrowed from whatever holds them (`vpl-visibility`'s
//! `ShadowMaps`, a GPU twin's host copy). A visibility whose answers are
//! its maps says so ([`crate::VplVisibility::shadow_maps`]), so that a
//! shader may read the maps directly in its own loop (vpl-shading's fused
//! gather) with the same answer as [`crate::VplVisibility::attenuate`].

use crate::LocalFrame;
use glam::Vec3;

/// The maps of a visibility structure, slot by slot.
pub trait ShadowMapSource {
    /// The map of the VPL in `slot`; `None` where the slot holds no map
    /// (its VPL is seen by nothing).
    fn map(&self, slot: usize) -> Option<MapView<'_>>;
}

/// One VPL's shadow map, borrowed for a batch of queries.
#[derive(Clone, Copy, Debug)]
pub struct MapView<'a> {
    /// Where the map's rays start: the VPL stepped off its surface.
    pub origin: Vec3,
    frame: LocalFrame,
    depth: &'a [f32],
    res: usize,
    half: f32,
    max: f32,
    texel: f32,
    eps2: f32,
    bias_scale: f32,
}

impl<'a> MapView<'a> {
    /// A view of a map held elsewhere (the GPU twin's host copy): `depth`
    /// holds `res × res` texels row-major, rendered from `origin` in `frame`
    /// as vpl-visibility's `ShadowMaps` renders them; `eps` is the scene's ray offset.
    pub fn new(origin: Vec3, frame: LocalFrame, depth: &'a [f32], res: u32, eps: f32, bias_scale: f32) -> MapView<'a> {
        assert_eq!(depth.len(), (res * res) as usize, "a map of {res}² texels");
        MapView {
            origin,
            frame,
            depth,
            res: res as usize,
            half: 0.5 * res as f32,
            max: (res - 1) as f32,
            texel: 2.0 / res as f32,
            eps2: 2.0 * eps,
            bias_scale,
        }
    }

    /// The map's frame (+Z along the VPL normal).
    pub fn frame(&self) -> LocalFrame {
        self.frame
    }

    /// Depth of texel (i, j), each clamped into the map.
    #[inline(always)]
    pub fn depth_at(&self, i: f32, j: f32) -> f32 {
        let i = (i.clamp(0.0, self.max)) as usize;
        let j = (j.clamp(0.0, self.max)) as usize;
        self.depth[j * self.res + i]
    }

    /// The texels' depths, row-major, and the side of the map.
    pub fn depths(&self) -> (&'a [f32], usize) {
        (self.depth, self.res)
    }

    /// Half the resolution: texel coordinate = (u + 1) · half.
    pub fn half(&self) -> f32 {
        self.half
    }

    /// The bias terms: (2ε, k · 2/res).
    pub fn bias_terms(&self) -> (f32, f32) {
        (self.eps2, self.bias_scale * self.texel)
    }

    /// Whether a receiver at `origin + d` (|d|² = `d2`) is visible; `cos_x`
    /// is −n_x·d, the receiver's unnormalised cosine toward the VPL.
    #[inline(always)]
    pub fn visible(&self, d: Vec3, d2: f32, cos_x: f32) -> bool {
        if d2 <= 0.0 {
            return true;
        }
        let inv = 1.0 / d2.sqrt();
        let dist = d2 * inv;
        let lz = d.dot(self.frame.n) * inv;
        if lz <= 0.0 {
            return false;
        }
        let k = inv / (1.0 + lz);
        let i = ((d.dot(self.frame.s) * k + 1.0) * self.half).clamp(0.0, self.max) as usize;
        let j = ((d.dot(self.frame.t) * k + 1.0) * self.half).clamp(0.0, self.max) as usize;
        let depth = self.depth[j * self.res + i];
        // Bias: the receiver's depth change across one texel (see vpl-visibility's `ShadowMaps`).
        let cos_r = (cos_x * inv).abs();
        let tan = ((1.0 - cos_r * cos_r).max(0.0).sqrt() / cos_r.max(0.1)).min(10.0);
        let bias = self.eps2 + self.bias_scale * dist * self.texel * (1.0 + lz) * (0.5 + tan);
        dist - bias <= depth
    }
}
