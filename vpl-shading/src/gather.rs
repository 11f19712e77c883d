//! The VPL-major inner loop both shaders share: one VPL at a time over a
//! batch of receivers, so its visibility data stays in cache.

use vpl_core::glam::Vec3;
use vpl_core::{GeometryClamp, Receivers, VplSet, VplVisibility};
use vpl_visibility::ShadowMaps;

/// Per-receiver sums of flux · min(G, G_max) · V, one array per channel.
#[derive(Clone, Debug, Default)]
pub(crate) struct Sums {
    pub r: Vec<f32>,
    pub g: Vec<f32>,
    pub b: Vec<f32>,
}

impl Sums {
    pub fn zeros(n: usize) -> Sums {
        Sums { r: vec![0.0; n], g: vec![0.0; n], b: vec![0.0; n] }
    }
}

/// Adds the contribution of the VPLs in `slots` to `sums` for every
/// receiver: Σ flux · min(G, G_max) · V. `w` is scratch space.
// The lanes index several arrays at once, which is what lets the loops vectorise.
#[allow(clippy::needless_range_loop)]
pub(crate) fn gather(
    rx: &Receivers,
    vpls: &VplSet,
    slots: &[u32],
    vis: &dyn VplVisibility,
    clamp: Option<GeometryClamp>,
    sums: &mut Sums,
    w: &mut Vec<f32>,
) {
    let n = rx.len();
    let g_max = clamp.map_or(f32::INFINITY, |c| c.g_max);
    if let Some(sm) = vis.as_any().downcast_ref::<ShadowMaps>() {
        return gather_shadow_maps(rx, vpls, slots, sm, g_max, sums);
    }
    w.resize(n, 0.0);
    for &slot in slots {
        let Some(v) = vpls.get(slot as usize) else { continue };
        let (y, ny) = (v.y, v.n);
        // Unshadowed, clamped geometry term; branch-free so it vectorises.
        let mut any = false;
        for i in 0..n {
            let dx = rx.px[i] - y.x;
            let dy = rx.py[i] - y.y;
            let dz = rx.pz[i] - y.z;
            let d2 = dx * dx + dy * dy + dz * dz;
            let cos_y = ny.x * dx + ny.y * dy + ny.z * dz;
            let cos_x = -(rx.nx[i] * dx + rx.ny[i] * dy + rx.nz[i] * dz);
            let g = (cos_y * cos_x / (d2 * d2)).min(g_max);
            let g = if cos_y > 0.0 && cos_x > 0.0 && d2 > 0.0 { g } else { 0.0 };
            any |= g > 0.0;
            w[i] = g;
        }
        if !any {
            continue;
        }
        vis.attenuate(slot as usize, rx, w);
        let f = v.flux;
        for i in 0..n {
            sums.r[i] += f.x * w[i];
            sums.g[i] += f.y * w[i];
            sums.b[i] += f.z * w[i];
        }
    }
}

/// Lanes of the SIMD shadow-map loop.
const LANES: usize = 8;

/// [`gather`] with shadow-map visibility, fused into one pass per VPL and
/// eight receivers wide: the arithmetic of [`vpl_visibility::MapView::visible`]
/// lane by lane, without the weight array and the per-VPL dynamic call.
fn gather_shadow_maps(rx: &Receivers, vpls: &VplSet, slots: &[u32], sm: &ShadowMaps, g_max: f32, sums: &mut Sums) {
    use wide::{CmpGt, CmpLe, f32x8};
    let n = rx.len();
    let full = n / LANES * LANES;
    let load = |a: &[f32], i: usize| f32x8::from(<[f32; LANES]>::try_from(&a[i..i + LANES]).expect("eight lanes"));
    let zero = f32x8::ZERO;
    let one = f32x8::ONE;
    for &slot in slots {
        let Some(v) = vpls.get(slot as usize) else { continue };
        let Some(view) = sm.view(slot as usize) else { continue };
        let (y, n_y, o, f) = (v.y, v.n, view.origin, v.flux);
        let fr = view.frame();
        let (eps2, texel) = view.bias_terms();
        let half = f32x8::splat(view.half());
        let s8 = |x: f32| f32x8::splat(x);
        let (yx, yy, yz) = (s8(y.x), s8(y.y), s8(y.z));
        let (nyx, nyy, nyz) = (s8(n_y.x), s8(n_y.y), s8(n_y.z));
        let (ox, oy, oz) = (s8(o.x), s8(o.y), s8(o.z));
        let gmax = s8(g_max);
        for i in (0..full).step_by(LANES) {
            let (px, py, pz) = (load(&rx.px, i), load(&rx.py, i), load(&rx.pz, i));
            let (nx, ny, nz) = (load(&rx.nx, i), load(&rx.ny, i), load(&rx.nz, i));
            let (dx, dy, dz) = (px - yx, py - yy, pz - yz);
            let d2 = (dx * dx + dy * dy) + dz * dz;
            let cos_y = (nyx * dx + nyy * dy) + nyz * dz;
            let cos_x = -((nx * dx + ny * dy) + nz * dz);
            let lit = cos_y.cmp_gt(zero) & cos_x.cmp_gt(zero) & d2.cmp_gt(zero);
            if lit.none() {
                continue;
            }
            let gt = (cos_y * cos_x / (d2 * d2)).min(gmax);
            // Visibility, as MapView::visible.
            let (ex, ey, ez) = (px - ox, py - oy, pz - oz);
            let e2 = (ex * ex + ey * ey) + ez * ez;
            let cos_xo = -((nx * ex + ny * ey) + nz * ez);
            let inv = one / e2.sqrt();
            let dist = e2 * inv;
            let lz = ((ex * s8(fr.n.x) + ey * s8(fr.n.y)) + ez * s8(fr.n.z)) * inv;
            let k = inv / (one + lz);
            let u = (((ex * s8(fr.s.x) + ey * s8(fr.s.y)) + ez * s8(fr.s.z)) * k + one) * half;
            let w = (((ex * s8(fr.t.x) + ey * s8(fr.t.y)) + ez * s8(fr.t.z)) * k + one) * half;
            let (ua, wa, la) = (u.to_array(), w.to_array(), lit.to_array());
            let mut depth = [0.0f32; LANES];
            for l in 0..LANES {
                if la[l] != 0.0 {
                    depth[l] = view.depth_at(ua[l], wa[l]);
                }
            }
            let cos_r = (cos_xo * inv).abs();
            let tan = ((one - cos_r * cos_r).max(zero).sqrt() / cos_r.max(s8(0.1))).min(s8(10.0));
            let bias = s8(eps2) + s8(texel) * dist * (one + lz) * (s8(0.5) + tan);
            let seen = (dist - bias).cmp_le(f32x8::from(depth)) & lz.cmp_gt(zero);
            let seen = seen | e2.cmp_le(zero);
            let m = lit & seen;
            if m.none() {
                continue;
            }
            let wgt = m.blend(gt, zero);
            let acc = |a: &mut [f32], c: f32| {
                let v = load(a, i) + s8(c) * wgt;
                a[i..i + LANES].copy_from_slice(&v.to_array());
            };
            acc(&mut sums.r, f.x);
            acc(&mut sums.g, f.y);
            acc(&mut sums.b, f.z);
        }
        // The remainder, one receiver at a time.
        for i in full..n {
            let d = Vec3::new(rx.px[i] - y.x, rx.py[i] - y.y, rx.pz[i] - y.z);
            let n_x = Vec3::new(rx.nx[i], rx.ny[i], rx.nz[i]);
            let d2 = d.length_squared();
            let cos_y = n_y.dot(d);
            let cos_x = -n_x.dot(d);
            if cos_y <= 0.0 || cos_x <= 0.0 || d2 <= 0.0 {
                continue;
            }
            let gt = (cos_y * cos_x / (d2 * d2)).min(g_max);
            let d_o = Vec3::new(rx.px[i] - o.x, rx.py[i] - o.y, rx.pz[i] - o.z);
            if view.visible(d_o, d_o.length_squared(), -n_x.dot(d_o)) {
                sums.r[i] += f.x * gt;
                sums.g[i] += f.y * gt;
                sums.b[i] += f.z * gt;
            }
        }
    }
}

/// Receivers `s..e` of `rx` as their own batch.
pub(crate) fn slice(rx: &Receivers, s: usize, e: usize) -> Receivers {
    Receivers {
        pixel: rx.pixel[s..e].to_vec(),
        px: rx.px[s..e].to_vec(),
        py: rx.py[s..e].to_vec(),
        pz: rx.pz[s..e].to_vec(),
        nx: rx.nx[s..e].to_vec(),
        ny: rx.ny[s..e].to_vec(),
        nz: rx.nz[s..e].to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::{GBuffer, Scene, SceneSetup, VisibilityUpdate};

    /// Shadow maps behind a wrapper the fast path does not recognise.
    struct Opaque(ShadowMaps);

    impl VplVisibility for Opaque {
        fn name(&self) -> &'static str {
            "opaque"
        }
        fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate {
            self.0.update(scene, vpls)
        }
        fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32 {
            self.0.visible(slot, x, n_x)
        }
        fn memory_bytes(&self) -> usize {
            self.0.memory_bytes()
        }
        fn as_any(&self) -> &dyn std::any::Any {
            self
        }
    }

    #[test]
    fn fused_shadow_map_loop_matches_the_generic_one() {
        let setup = SceneSetup::load("cornell").unwrap();
        let camera = setup.camera.with_resolution((37, 29)).unwrap();
        let gbuf: GBuffer = crate::render_gbuffer(&setup.scene, &camera);
        let set =
            vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 200, ..Default::default() }).unwrap().sample(&setup.scene, 2).clone();
        let mut sm = ShadowMaps::new(64).unwrap();
        sm.update(&setup.scene, &set);
        let opaque = Opaque(sm.clone());
        let rx = gbuf.receivers(0..gbuf.samples.len() as u32);
        let slots: Vec<u32> = (0..set.len() as u32).collect();
        let clamp = Some(GeometryClamp::new(50.0));
        let (mut a, mut b) = (Sums::zeros(rx.len()), Sums::zeros(rx.len()));
        gather(&rx, &set, &slots, &sm, clamp, &mut a, &mut Vec::new());
        gather(&rx, &set, &slots, &opaque, clamp, &mut b, &mut Vec::new());
        let total: f32 = a.r.iter().sum();
        assert!(total > 0.0);
        for i in 0..rx.len() {
            assert!((a.r[i] - b.r[i]).abs() <= 1e-5 * b.r[i].abs().max(1e-3), "receiver {i}: {} vs {}", a.r[i], b.r[i]);
            assert!((a.b[i] - b.b[i]).abs() <= 1e-5 * b.b[i].abs().max(1e-3));
        }
    }
}
