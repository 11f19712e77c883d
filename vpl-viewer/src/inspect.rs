//! One VPL looked at closely: its paraboloid shadow map as a picture, and
//! the interleaving class whose pixels shade with it.

use glam::Vec3;
use vpl_core::image::linear_to_srgb;
use vpl_core::{Scene, VplSet, VplVisibility};
use vpl_visibility::{ShadowMapError, ShadowMaps};

/// A VPL's shadow map as the window shows it.
#[derive(Clone, Debug)]
pub struct MapPicture {
    /// Texels per side.
    pub res: u32,
    /// Distance from the VPL to the first surface per texel, row-major
    /// (infinite where the ray leaves the scene), as
    /// [`vpl_visibility::ShadowMaps`] renders it for shading.
    pub depth: Vec<f32>,
    /// Display pixels (sRGB, RGBA): near surfaces bright, far ones dark,
    /// texels that see nothing dark blue, and the corners outside the
    /// paraboloid's unit disk (no direction of the hemisphere) grey.
    pub rgba: Vec<u8>,
}

/// Grey of the texels outside the paraboloid's disk.
const OUTSIDE: [u8; 4] = [60, 60, 60, 255];
/// Texels whose ray leaves the scene.
const OPEN: [u8; 4] = [20, 30, 90, 255];

/// Renders the hemispherical paraboloid shadow map of the VPL in `slot` of
/// `vpls` at `res × res` texels, with the visibility the renderer uses
/// (one ray per texel from the VPL stepped off its surface). `None` when
/// the slot is empty.
pub fn shadow_map(scene: &Scene, vpls: &VplSet, slot: usize, res: u32) -> Result<Option<MapPicture>, ShadowMapError> {
    let Some(vpl) = vpls.get(slot) else { return Ok(None) };
    let mut maps = ShadowMaps::new(res)?;
    let mut one = VplSet::new(1);
    one.set(0, Some(*vpl));
    maps.update(scene, &one);
    let Some(view) = maps.view(0) else { return Ok(None) };
    let (depth, side) = view.depths();
    let far = depth.iter().copied().filter(|d| d.is_finite()).fold(0.0f32, f32::max).max(1e-6);
    let mut rgba = Vec::with_capacity(depth.len() * 4);
    for (k, d) in depth.iter().enumerate() {
        let (i, j) = ((k % side) as f32, (k / side) as f32);
        let u = (i + 0.5) / side as f32 * 2.0 - 1.0;
        let v = (j + 0.5) / side as f32 * 2.0 - 1.0;
        let px = if u * u + v * v > 1.0 {
            OUTSIDE
        } else if !d.is_finite() {
            OPEN
        } else {
            // 1 − d/far, with a square root so that near detail stands out.
            let c = linear_to_srgb(Vec3::splat((1.0 - d / far).max(0.0).sqrt() * 0.9 + 0.05));
            let b = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            [b(c.x), b(c.y), b(c.z), 255]
        };
        rgba.extend(px);
    }
    Ok(Some(MapPicture { res, depth: depth.to_vec(), rgba }))
}

/// The interleaving class (0..16) whose pixels shade with slot `slot` of a
/// set of `slots` slots, for a renderer of `seed`: the subsets
/// [`vpl_shading::InterleavedShader`] draws from its seed (the GPU
/// backend draws the same ones).
pub fn interleave_class(slot: usize, slots: usize, seed: u64) -> Option<usize> {
    let mut shader = vpl_shading::InterleavedShader::new(None, seed);
    shader.subsets(slots).iter().position(|s| s.binary_search(&(slot as u32)).is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::{SceneSetup, Vpl};

    #[test]
    fn a_vpl_s_map_sees_along_its_normal_what_a_ray_sees() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let scene = &setup.scene;
        // Straight down from the box's middle: the floor (or a block on it),
        // which looks up at the ceiling.
        let hit = scene.intersect(&vpl_core::Ray::new(Vec3::ZERO, -Vec3::Y)).unwrap().point;
        let n = if hit.ng.y < 0.0 { -hit.ng } else { hit.ng };
        let mut set = VplSet::new(2);
        set.set(1, Some(Vpl { y: hit.p, n, flux: Vec3::ONE, id: 1, bounce: 1 }));
        assert!(shadow_map(scene, &set, 0, 32).unwrap().is_none(), "an empty slot has no map");
        let m = shadow_map(scene, &set, 1, 32).unwrap().unwrap();
        assert_eq!((m.res, m.depth.len(), m.rgba.len()), (32, 32 * 32, 32 * 32 * 4));
        // Texel (16, 16) looks 1/32 of the map's half-width off the normal.
        let along = scene.intersect(&vpl_core::Ray::new(hit.p + n * scene.epsilon(), n)).unwrap().t;
        let texel = m.depth[16 * 32 + 16];
        assert!((texel - along).abs() < 0.05 * along, "depth along the normal {texel}, a ray's {along}");
        assert_eq!(&m.rgba[0..4], &OUTSIDE, "the corner lies outside the paraboloid's disk");
        assert!(shadow_map(scene, &set, 1, 0).is_err());
    }

    #[test]
    fn every_slot_has_one_class_and_the_classes_share_the_slots() {
        let mut count = [0usize; vpl_shading::CLASSES];
        for slot in 0..64 {
            count[interleave_class(slot, 64, 7).unwrap()] += 1;
        }
        assert!(count.iter().all(|&n| n == 4), "{count:?}");
        assert_eq!(interleave_class(64, 64, 7), None);
    }
}
