//! Paraboloid shadow maps, one per VPL, rebuilt lazily.

use crate::paraboloid::paraboloid_to_direction;
use rayon::prelude::*;
use vpl_core::glam::{Vec2, Vec3};
use vpl_core::{LocalFrame, MapView, Receivers, Scene, ShadowMapSource, VisibilityUpdate, Vpl, VplSet, VplVisibility};

/// The SMC paper's default map size (§4): 128×128 texels.
pub const DEFAULT_RESOLUTION: u32 = 128;

/// Side of the tiles of texels traced together: a tile's rays are one
/// bundle of [`vpl_core::bvh::FAN`].
const TILE: usize = 8;
const _: () = assert!(TILE * TILE == vpl_core::bvh::FAN);

/// Largest accepted map side.
pub const MAX_RESOLUTION: u32 = 4096;

/// Errors of [`ShadowMaps::new`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ShadowMapError {
    /// The resolution is outside 1..=4096.
    #[error("shadow-map resolution {0} is outside 1..={MAX_RESOLUTION}")]
    Resolution(u32),
}

/// One VPL's depth map.
#[derive(Clone, Debug)]
struct Map {
    /// The VPL position and normal the map was rendered for.
    key: (Vec3, Vec3),
    /// Ray origin: the VPL stepped off its surface.
    origin: Vec3,
    /// Frame whose +Z is the VPL normal.
    frame: LocalFrame,
    /// Distance to the first surface per texel, row-major; infinite where nothing is hit.
    depth: Vec<f32>,
}

/// Hemispherical paraboloid shadow maps, one per VPL slot.
///
/// Texel (i, j) of a map stores the distance from the VPL to the first
/// surface along the direction at paraboloid coordinates of its centre
/// (a ray cast per texel: the CPU counterpart of rasterising the map). A
/// receiver x is visible when |x − y| − b ≤ D, D the depth of the texel its
/// direction falls in, and the bias
///
/// ```text
/// b = 2ε + k · |x − y| · Δθ · (½ + min(tan φ, 10)),   Δθ = (2 / res) · (1 + cos θ)
/// ```
///
/// where Δθ is the angle one texel spans at polar angle θ (du/dθ = 1/(1 + cos θ)
/// for u = tan(θ/2)), φ the angle between the receiver normal and the
/// direction to the VPL, ε the scene's ray offset and k = [`ShadowMaps::bias_scale`].
/// The bias covers the receiver's own depth change across a texel, so it
/// shrinks in proportion to 1/res (the SMC paper adjusts its bias with the
/// resolution in the same way, §5.4).
#[derive(Clone, Debug)]
pub struct ShadowMaps {
    res: u32,
    /// The local direction of each texel's centre, tile by tile of
    /// [`TILE`]² texels and row by row inside a tile (the same for every map).
    texels: Vec<Vec3>,
    maps: Vec<Option<Map>>,
    eps: f32,
    /// Scale k of the slope-dependent depth bias (default 1).
    pub bias_scale: f32,
}

impl ShadowMaps {
    /// Maps of `res × res` texels.
    pub fn new(res: u32) -> Result<Self, ShadowMapError> {
        if res == 0 || res > MAX_RESOLUTION {
            return Err(ShadowMapError::Resolution(res));
        }
        let scale = 2.0 / res as f32;
        let centre = |k: u32| (k as f32 + 0.5) * scale - 1.0;
        // Tile by tile (as `render` traces them), row by row inside a tile.
        let res_u = res as usize;
        let mut texels = Vec::with_capacity(res_u * res_u);
        for j0 in (0..res_u).step_by(TILE) {
            for i0 in (0..res_u).step_by(TILE) {
                for j in j0..(j0 + TILE).min(res_u) {
                    for i in i0..(i0 + TILE).min(res_u) {
                        texels.push(paraboloid_to_direction(Vec2::new(centre(i as u32), centre(j as u32))));
                    }
                }
            }
        }
        Ok(ShadowMaps { res, texels, maps: Vec::new(), eps: 0.0, bias_scale: 1.0 })
    }

    /// Texels per side.
    pub fn resolution(&self) -> u32 {
        self.res
    }

    /// Number of maps held.
    pub fn maps(&self) -> usize {
        self.maps.iter().filter(|m| m.is_some()).count()
    }

    /// Renders the map of `vpl` by casting one ray per texel, in tiles of
    /// [`TILE`] × [`TILE`] texels traced together from the VPL
    /// ([`Scene::closest_fan`]).
    fn render(scene: &Scene, vpl: &Vpl, res: u32, texels: &[Vec3]) -> Map {
        let eps = scene.epsilon();
        let origin = vpl.y + vpl.n * eps;
        let frame = LocalFrame::from_normal(vpl.n);
        let res = res as usize;
        let mut depth = vec![0.0f32; res * res];
        depth.par_chunks_mut(TILE * res).enumerate().for_each(|(band, rows)| {
            let h = rows.len() / res;
            // The band's texels are consecutive in the table.
            let mut local = &texels[band * TILE * res..];
            let mut dirs = [Vec3::ZERO; TILE * TILE];
            let mut hits = [None; TILE * TILE];
            for i0 in (0..res).step_by(TILE) {
                let w = TILE.min(res - i0);
                let n = w * h;
                for (d, l) in dirs.iter_mut().zip(&local[..n]) {
                    *d = frame.to_world(*l);
                }
                local = &local[n..];
                scene.closest_fan(origin, &dirs[..n], &mut hits);
                for dj in 0..h {
                    for di in 0..w {
                        rows[dj * res + i0 + di] = hits[dj * w + di].map_or(f32::INFINITY, |(_, t)| t);
                    }
                }
            }
        });
        Map { key: (vpl.y, vpl.n), origin, frame, depth }
    }

    #[inline]
    fn lookup(&self, m: &Map, x: Vec3, n_x: Vec3) -> f32 {
        let v = self.view_of(m);
        let d = x - m.origin;
        if v.visible(d, d.length_squared(), -n_x.dot(d)) { 1.0 } else { 0.0 }
    }

    #[inline]
    fn view_of<'a>(&self, m: &'a Map) -> MapView<'a> {
        MapView::new(m.origin, m.frame, &m.depth, self.res, self.eps, self.bias_scale)
    }

    /// The map of `slot`, for loops that query one VPL many times.
    #[inline]
    pub fn view(&self, slot: usize) -> Option<MapView<'_>> {
        match self.maps.get(slot) {
            Some(Some(m)) => Some(self.view_of(m)),
            _ => None,
        }
    }
}

impl ShadowMapSource for ShadowMaps {
    fn map(&self, slot: usize) -> Option<MapView<'_>> {
        self.view(slot)
    }
}

impl VplVisibility for ShadowMaps {
    fn name(&self) -> &'static str {
        "shadowmap"
    }

    /// Rebuilds the maps of slots whose VPL position or normal differs from
    /// the one the map was rendered for (a VPL whose flux alone changed keeps
    /// its map); drops the maps of emptied slots.
    fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate {
        self.eps = scene.epsilon();
        self.maps.resize(vpls.len(), None);
        let stale: Vec<usize> = (0..vpls.len())
            .filter(|&s| match (vpls.get(s), &self.maps[s]) {
                (Some(v), Some(m)) => m.key != (v.y, v.n),
                (Some(_), None) => true,
                (None, _) => false,
            })
            .collect();
        for s in 0..vpls.len() {
            if vpls.get(s).is_none() {
                self.maps[s] = None;
            }
        }
        let (res, texels) = (self.res, &self.texels);
        let fresh: Vec<(usize, Map)> =
            stale.par_iter().map(|&s| (s, Self::render(scene, vpls.get(s).expect("stale slots hold a VPL"), res, texels))).collect();
        for (s, m) in fresh {
            self.maps[s] = Some(m);
        }
        VisibilityUpdate { rebuilt: stale.len(), memory_bytes: self.memory_bytes() }
    }

    #[inline]
    fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32 {
        match self.maps.get(slot) {
            Some(Some(m)) => self.lookup(m, x, n_x),
            _ => 0.0,
        }
    }

    fn attenuate(&self, slot: usize, rx: &Receivers, w: &mut [f32]) {
        let Some(Some(m)) = self.maps.get(slot) else {
            w.iter_mut().for_each(|x| *x = 0.0);
            return;
        };
        for (i, wi) in w.iter_mut().enumerate() {
            if *wi > 0.0 {
                *wi *= self.lookup(m, rx.p(i), rx.n(i));
            }
        }
    }

    fn shadow_maps(&self) -> Option<&dyn ShadowMapSource> {
        Some(self)
    }

    fn memory_bytes(&self) -> usize {
        self.maps.iter().flatten().map(|m| m.depth.len() * 4 + std::mem::size_of::<Map>()).sum::<usize>()
            + self.maps.len() * std::mem::size_of::<Option<Map>>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;

    fn vpl(y: Vec3, n: Vec3) -> Vpl {
        Vpl { y, n, flux: Vec3::ONE, id: 0, bounce: 1 }
    }

    #[test]
    fn only_moved_vpls_rebuild_and_memory_is_counted() {
        let scene = SceneSetup::builtin("cornell").unwrap().scene;
        let mut set = VplSet::new(3);
        set.set(0, Some(vpl(Vec3::new(0.0, 0.99, 0.0), -Vec3::Y)));
        set.set(1, Some(vpl(Vec3::new(0.5, -1.0, 0.5), Vec3::Y)));
        let mut sm = ShadowMaps::new(32).unwrap();
        let u = sm.update(&scene, &set);
        assert_eq!(u.rebuilt, 2);
        assert!(u.memory_bytes >= 2 * 32 * 32 * 4);
        set.begin_frame();
        // Flux alone: the map stays.
        set.set(0, Some(Vpl { flux: Vec3::splat(2.0), ..vpl(Vec3::new(0.0, 0.99, 0.0), -Vec3::Y) }));
        assert_eq!(sm.update(&scene, &set).rebuilt, 0);
        set.set(1, None);
        let u = sm.update(&scene, &set);
        assert_eq!((u.rebuilt, sm.maps()), (0, 1));
        assert!(ShadowMaps::new(0).is_err());
    }
}
