//! The VPL-major inner loop both shaders share: one VPL at a time over a
//! batch of receivers, so its visibility data stays in cache.

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
pub(crate) fn gather(rx: &Receivers, vpls: &VplSet, slots: &[u32], vis: &dyn VplVisibility, clamp: Option<GeometryClamp>, sums: &mut Sums, w: &mut Vec<f32>) {
    let n = rx.len();
    w.resize(n, 0.0);
    let g_max = clamp.map_or(f32::INFINITY, |c| c.g_max);
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
