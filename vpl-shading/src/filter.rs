//! The cross-bilateral filter that removes interleaving's structured noise
//! (Hedman et al. 2017, §4; Eisemann & Durand 2004, Petschnigg et al. 2004).

use rayon::prelude::*;
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, Image};

/// A cross-bilateral filter guided by the G-buffer.
///
/// The output at pixel p is Σ_q w(p, q)·E(q) / Σ_q w(p, q) over a square
/// window of side 4·`periods` + 1 around p, with
///
/// ```text
/// w(p, q) = t(Δx)·t(Δy) · max(0, n_p·n_q)^α · exp(−|x_p − x_q|² / 2σ_p²)
/// ```
///
/// - t is 1 inside the window and ½ on its border, so on a flat surface each
///   of the 16 interleaving classes gets the same total weight (the border
///   rows are a whole tile apart and share classes);
/// - the normal term (α = `normal_power`) and the world-space distance term
///   are the two guides §4 names; they keep light from leaking across
///   creases and depth edges;
/// - σ_p = `sigma` · the pixel's world-space footprint, depth · pixel angle /
///   |cos| of the view angle, so the filter behaves the same near and far
///   and on surfaces seen at grazing angles.
///
/// Pixels that reflect nothing neither receive nor give weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossBilateral {
    /// Window half-size in tiles: the window is (4·periods + 1)² pixels.
    pub periods: u32,
    /// Exponent α of the normal term.
    pub normal_power: u32,
    /// Distance scale σ in pixel footprints.
    pub sigma: f32,
}

impl Default for CrossBilateral {
    fn default() -> Self {
        CrossBilateral { periods: 1, normal_power: 16, sigma: 3.0 }
    }
}

impl CrossBilateral {
    /// The guide, compact, per pixel: position, normal and 1/2σ_p² (0 where
    /// nothing reflects). Shared with the GPU twin.
    pub fn guide(&self, gbuf: &GBuffer) -> Vec<(Vec3, Vec3, f32)> {
        gbuf.samples
            .iter()
            .map(|g| {
                if !g.reflects() {
                    return (g.p, g.n, 0.0);
                }
                let view = (gbuf.eye - g.p).normalize_or_zero();
                let footprint = g.depth * gbuf.pixel_angle / g.n.dot(view).abs().max(0.1);
                (g.p, g.n, 1.0 / (2.0 * (self.sigma * footprint).powi(2)).max(f32::MIN_POSITIVE))
            })
            .collect()
    }

    /// Filters `e` (one value per G-buffer pixel).
    pub fn apply(&self, gbuf: &GBuffer, e: &Image) -> Image {
        let (w, h) = (gbuf.width as i32, gbuf.height as i32);
        let r = 2 * self.periods as i32;
        let guide = self.guide(gbuf);
        let mut out = Image::new(gbuf.width, gbuf.height);
        out.data.par_chunks_mut(w.max(1) as usize).enumerate().for_each(|(y, row)| {
            let y = y as i32;
            for (x, o) in row.iter_mut().enumerate() {
                let x = x as i32;
                let (pp, np, inv_2s2) = guide[(y * w + x) as usize];
                if inv_2s2 == 0.0 {
                    continue;
                }
                let mut sum = Vec3::ZERO;
                let mut wsum = 0.0f32;
                for qy in (y - r).max(0)..=(y + r).min(h - 1) {
                    let ty = if (qy - y).abs() == r { 0.5 } else { 1.0 };
                    let base = (qy * w) as usize;
                    for qx in (x - r).max(0)..=(x + r).min(w - 1) {
                        let i = base + qx as usize;
                        let (pq, nq, valid) = guide[i];
                        if valid == 0.0 {
                            continue;
                        }
                        let tx = if (qx - x).abs() == r { 0.5 } else { 1.0 };
                        let wn = pow_u(np.dot(nq).max(0.0), self.normal_power);
                        let wd = (-(pp - pq).length_squared() * inv_2s2).exp();
                        let wt = tx * ty * wn * wd;
                        sum += e.data[i] * wt;
                        wsum += wt;
                    }
                }
                *o = if wsum > 0.0 { sum / wsum } else { e.data[(y * w + x) as usize] };
            }
        });
        out
    }
}

/// x^k by squaring (`powi` is a library call in the inner loop).
#[inline(always)]
fn pow_u(mut x: f32, mut k: u32) -> f32 {
    let mut r = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            r *= x;
        }
        x *= x;
        k >>= 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::GSample;

    fn plane(w: u32, h: u32) -> GBuffer {
        let samples = (0..w * h)
            .map(|i| GSample {
                p: Vec3::new((i % w) as f32 * 0.01, (i / w) as f32 * 0.01, 0.0),
                n: Vec3::Z,
                ng: Vec3::Z,
                albedo: Vec3::ONE,
                emitted: Vec3::ZERO,
                material: 0,
                depth: 1.0,
            })
            .collect();
        GBuffer { width: w, height: h, samples, pixel_angle: 0.01, eye: Vec3::new(0.0, 0.0, 1.0) }
    }

    #[test]
    fn flat_surfaces_average_all_sixteen_classes_equally() {
        let g = plane(12, 12);
        // One class bright, the others dark: the filtered value is their mean
        // wherever the 5×5 window fits, whatever the distance falloff.
        let mut e = Image::new(12, 12);
        for y in 0..12 {
            for x in 0..12 {
                e.set(x, y, if x % 4 == 1 && y % 4 == 2 { Vec3::splat(16.0) } else { Vec3::ZERO });
            }
        }
        let f = CrossBilateral { sigma: 1e6, ..CrossBilateral::default() }.apply(&g, &e);
        for y in 2..10 {
            for x in 2..10 {
                assert!((f.get(x, y).x - 1.0).abs() < 1e-4, "({x},{y}): {}", f.get(x, y).x);
            }
        }
        // A crease: a neighbour whose normal is perpendicular gives no weight.
        let mut g2 = g.clone();
        g2.samples[13].n = Vec3::X;
        let f2 = CrossBilateral::default().apply(&g2, &Image { data: vec![Vec3::ONE; 144], ..e.clone() });
        assert!((f2.get(1, 1).x - 1.0).abs() < 1e-5);
    }
}
