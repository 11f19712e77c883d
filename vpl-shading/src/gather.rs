//! The VPL-major inner loop both shaders share: one VPL at a time over a
//! batch of receivers, so its visibility data stays in cache.

use vpl_core::glam::Vec3;
use vpl_core::{GeometryClamp, Receivers, VplSet, VplVisibility};

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
    if let Some(sm) = vis.shadow_maps() {
        return crate::gather_maps::gather_shadow_maps(rx, vpls, slots, sm, g_max, sums);
    }
    w.resize(n, 0.0);
    for &slot in slots {
        let Some(v) = vpls.get(slot as usize) else { continue };
        if !geometry_terms(rx, v, g_max, w) {
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

/// The unshadowed geometry term min(G, G_max) of VPL `v` at every receiver
/// of `rx` into `w` (zero where either side faces away); branch-free so it
/// vectorises. Whether any term is above zero.
// The lanes index several arrays at once, which is what lets the loop vectorise.
#[allow(clippy::needless_range_loop)]
#[inline]
fn geometry_terms(rx: &Receivers, v: &vpl_core::Vpl, g_max: f32, w: &mut [f32]) -> bool {
    let (y, ny) = (v.y, v.n);
    let mut any = false;
    for i in 0..rx.len() {
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
    any
}

/// [`gather`] without a clamp into `free` and under `g_max` into
/// `clamped`, in one pass: each (receiver, VPL) pair's visibility is asked
/// once for both. The clamped weight is the unclamped one, visibility
/// included, times r = min(1, G_max / G): exactly it where G ≤ G_max, and
/// within a rounding of min(G, G_max) · V elsewhere. `free` is bit for bit
/// what [`gather`] gives without a clamp. `w` and `r` are scratch space.
// The lanes index several arrays at once, which is what lets the loops vectorise.
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
pub(crate) fn gather_free_and_clamped(
    rx: &Receivers,
    vpls: &VplSet,
    slots: &[u32],
    vis: &dyn VplVisibility,
    g_max: f32,
    free: &mut Sums,
    clamped: &mut Sums,
    (w, r): (&mut Vec<f32>, &mut Vec<f32>),
) {
    let n = rx.len();
    if let Some(sm) = vis.shadow_maps() {
        // The shadow-map gather reads its maps per pair: no query to share.
        crate::gather_maps::gather_shadow_maps(rx, vpls, slots, sm, f32::INFINITY, free);
        return crate::gather_maps::gather_shadow_maps(rx, vpls, slots, sm, g_max, clamped);
    }
    w.resize(n, 0.0);
    r.resize(n, 0.0);
    for &slot in slots {
        let Some(v) = vpls.get(slot as usize) else { continue };
        if !geometry_terms(rx, v, f32::INFINITY, w) {
            continue;
        }
        for i in 0..n {
            r[i] = if w[i] > g_max { g_max / w[i] } else { 1.0 };
        }
        vis.attenuate(slot as usize, rx, w);
        let f = v.flux;
        for i in 0..n {
            let (wf, wc) = (w[i], w[i] * r[i]);
            free.r[i] += f.x * wf;
            free.g[i] += f.y * wf;
            free.b[i] += f.z * wf;
            clamped.r[i] += f.x * wc;
            clamped.g[i] += f.y * wc;
            clamped.b[i] += f.z * wc;
        }
    }
}

/// The clamped geometry term min(G, G_max) between a receiver at `x` with
/// normal `n_x` and the VPL `v`, as [`gather`] computes it lane by lane
/// (cos_y cos_x / d², zero where either side faces away); for the shaders
/// that visit one (receiver, VPL) pair at a time.
#[inline]
pub(crate) fn clamped_g(v: &vpl_core::Vpl, x: Vec3, n_x: Vec3, g_max: f32) -> f32 {
    let d = x - v.y;
    let d2 = d.length_squared();
    let (cos_y, cos_x) = (v.n.dot(d), -n_x.dot(d));
    if cos_y > 0.0 && cos_x > 0.0 && d2 > 0.0 { (cos_y * cos_x / (d2 * d2)).min(g_max) } else { 0.0 }
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
    use vpl_core::glam::Vec3;
    use vpl_core::{GBuffer, Scene, VisibilityUpdate};
    use vpl_visibility::ShadowMaps;

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
    }

    /// The fused shadow-map loop against the generic one (exact
    /// divisions and square roots, `MapView::visible`), pair by pair over
    /// 200 VPLs and 2,257 receivers on `cornell` and `office`: where both
    /// see the VPL, weights within 10⁻⁶ relative (the bound of the
    /// approximations, see `gather_maps`); a visibility decision differs
    /// for at most 10⁻⁴ of the lit pairs (only where the depth test is
    /// decided within the approximations' error). The AVX2 and portable
    /// implementations give the same bits.
    #[test]
    fn fused_shadow_map_loop_matches_the_generic_one() {
        for name in ["cornell", "office"] {
            let setup = vpl_core::SceneSetup::builtin(name).unwrap();
            let camera = setup.camera.with_resolution((61, 37)).unwrap();
            let gbuf: GBuffer = crate::render_gbuffer(&setup.scene, &camera);
            let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 200, ..Default::default() })
                .unwrap()
                .sample(&setup.scene, 2)
                .clone();
            let mut sm = ShadowMaps::new(64).unwrap();
            sm.update(&setup.scene, &set);
            let opaque = Opaque(sm.clone());
            let rx = gbuf.receivers(0..gbuf.samples.len() as u32);
            let clamp = Some(GeometryClamp::new(50.0));
            let g_max = GeometryClamp::new(50.0).g_max;
            let (mut lit, mut flips, mut worst) = (0usize, 0usize, 0f32);
            for slot in 0..set.len() as u32 {
                let (mut a, mut b, mut c) = (Sums::zeros(rx.len()), Sums::zeros(rx.len()), Sums::zeros(rx.len()));
                gather(&rx, &set, &[slot], &sm, clamp, &mut a, &mut Vec::new());
                gather(&rx, &set, &[slot], &opaque, clamp, &mut b, &mut Vec::new());
                crate::gather_maps::gather_shadow_maps_portable(&rx, &set, &[slot], &sm, g_max, &mut c);
                assert_eq!((&a.r, &a.g, &a.b), (&c.r, &c.g, &c.b), "{name}, VPL {slot}: AVX2 and portable");
                for i in 0..rx.len() {
                    let (x, y) = (a.r[i] + a.g[i] + a.b[i], b.r[i] + b.g[i] + b.b[i]);
                    lit += (y > 0.0) as usize;
                    if (x > 0.0) != (y > 0.0) {
                        flips += 1;
                    } else if y > 0.0 {
                        worst = worst.max(((x - y) / y).abs());
                    }
                }
            }
            eprintln!("{name}: {lit} lit pairs, {flips} visibility decisions differ, weights within {worst:e}");
            assert!(lit > 10_000, "{name}: {lit}");
            assert!(worst <= 1e-6, "{name}: weights within {worst:e}");
            assert!(flips as f64 <= 1e-4 * lit as f64, "{name}: {flips} of {lit} decisions differ");
        }
    }
}
