//! The cross-bilateral filter that removes interleaving's structured noise
//! (Hedman et al. 2017, §4; Eisemann & Durand 2004, Petschnigg et al. 2004).

use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
mod avx2;
mod lanes;
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
        (0..gbuf.samples.len()).map(|i| self.guide_of(gbuf, i)).collect()
    }

    /// The guide of pixel `i`.
    fn guide_of(&self, gbuf: &GBuffer, i: usize) -> (Vec3, Vec3, f32) {
        let g = &gbuf.samples[i];
        if !g.reflects() {
            return (g.p, g.n, 0.0);
        }
        let view = (gbuf.eye - g.p).normalize_or_zero();
        let footprint = g.depth * gbuf.pixel_angle / g.n.dot(view).abs().max(0.1);
        (g.p, g.n, 1.0 / (2.0 * (self.sigma * footprint).powi(2)).max(f32::MIN_POSITIVE))
    }

    /// Filters `e` (one value per G-buffer pixel), eight pixels of a row at
    /// a time (see [`CrossBilateral::apply_exact`] for the same filter one
    /// pixel at a time with the library's `exp`).
    pub fn apply(&self, gbuf: &GBuffer, e: &Image) -> Image {
        self.apply_with(gbuf, e, &mut Planes::default())
    }

    /// [`CrossBilateral::apply`] with the planes kept by the caller.
    pub(crate) fn apply_with(&self, gbuf: &GBuffer, e: &Image, planes: &mut Planes) -> Image {
        planes.fill(self, gbuf, e);
        let mut out = Image::new(gbuf.width, gbuf.height);
        let w = gbuf.width.max(1) as usize;
        let planes = &*planes;
        out.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| planes.row(self.normal_power, y, row));
        out
    }

    /// [`CrossBilateral::apply`] pixel by pixel with exact arithmetic: the
    /// reference the fast filter is tested against.
    pub fn apply_exact(&self, gbuf: &GBuffer, e: &Image) -> Image {
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

/// Pixels per step of the fast filter.
const LANES: usize = 8;

/// Components of a padded row: position (3), normal (3), 1/2σ² (1) and
/// the input value (3), at these offsets.
const P: usize = 0;
const N: usize = 3;
const K: usize = 6;
const E: usize = 7;
const COMPONENTS: usize = 10;

/// The guide and the input as planes, padded by the window's reach on
/// every side (and by eight pixels more on the right, so that a row's last
/// step reads whole lanes) with pixels that give no weight (1/2σ² = 0):
/// one buffer, row by row, each row holding its components one after the
/// other. Kept by its owner between frames (the buffer is reused).
#[derive(Clone, Debug, Default)]
pub(crate) struct Planes {
    /// Length of a component's row and the window's reach.
    stride: usize,
    r: usize,
    width: usize,
    height: usize,
    /// Window taps: (row offset, column offset, t(Δx) · t(Δy)), row by row.
    taps: Vec<(usize, usize, f32)>,
    data: Vec<f32>,
}

impl Planes {
    /// Fills the planes for filter `f` over `gbuf` and input `e`, reusing
    /// the buffer where the sizes allow.
    fn fill(&mut self, f: &CrossBilateral, gbuf: &GBuffer, e: &Image) {
        let (w, h) = (gbuf.width as usize, gbuf.height as usize);
        let r = 2 * f.periods as usize;
        let stride = w + 2 * r + LANES;
        let len = stride * COMPONENTS * (h + 2 * r);
        if (self.stride, self.r, self.width, self.height) != (stride, r, w, h) || self.data.len() != len {
            *self = Planes { stride, r, width: w, height: h, taps: Vec::new(), data: vec![0f32; len] };
            let border = |d: usize| if d == 0 || d == 2 * r { 0.5 } else { 1.0 };
            for dy in 0..=2 * r {
                for dx in 0..=2 * r {
                    self.taps.push((dy, dx, border(dx) * border(dy)));
                }
            }
        }
        // The padding stays zero; the image's rows are rewritten.
        let rows = self.data.par_chunks_mut(stride * COMPONENTS).skip(r).take(h);
        rows.enumerate().for_each(|(y, row)| {
            for x in 0..w {
                let i = y * w + x;
                let (p, n, k) = f.guide_of(gbuf, i);
                let v = e.data[i];
                for a in 0..3 {
                    row[(P + a) * stride + x + r] = p[a];
                    row[(N + a) * stride + x + r] = n[a];
                    row[(E + a) * stride + x + r] = v[a];
                }
                row[K * stride + x + r] = k;
            }
        });
    }

    /// Eight values of component `c` of padded row `row` from column `col`.
    #[inline(always)]
    fn lanes(&self, c: usize, row: usize, col: usize) -> &[f32; LANES] {
        let at = (row * COMPONENTS + c) * self.stride + col;
        self.data[at..at + LANES].try_into().expect("eight lanes")
    }

    /// Value of component `c` at padded row `row`, column `col`.
    #[inline(always)]
    fn value(&self, c: usize, row: usize, col: usize) -> f32 {
        self.data[(row * COMPONENTS + c) * self.stride + col]
    }

    /// Filters output row `y`: eight pixels at a time, the operations of
    /// [`CrossBilateral::apply_exact`] in the same order with eˣ by
    /// [`exp_neg`]'s steps; with AVX2 intrinsics where the CPU has AVX2 and
    /// FMA, else on `wide`'s 8-lane type (the same bits).
    fn row(&self, alpha: u32, y: usize, out: &mut [Vec3]) {
        #[cfg(target_arch = "x86_64")]
        if avx2::row(self, alpha, y, out) {
            return;
        }
        lanes::row(self, alpha, y, out)
    }

    /// Writes the filtered value of the pixels `x0..` of row `y` (at most
    /// eight) from their weighted sums and weights.
    fn finish(&self, y: usize, x0: usize, sum: [[f32; LANES]; 3], wsum: [f32; LANES], out: &mut [Vec3]) {
        let (row, c) = (y + self.r, x0 + self.r);
        for l in 0..LANES.min(self.width - x0) {
            if self.value(K, row, c + l) == 0.0 {
                continue;
            }
            let e = Vec3::new(self.value(E, row, c + l), self.value(E + 1, row, c + l), self.value(E + 2, row, c + l));
            let sum = Vec3::new(sum[0][l], sum[1][l], sum[2][l]);
            out[x0 + l] = if wsum[l] > 0.0 { sum / wsum[l] } else { e };
        }
    }
}

/// eˣ for x ≤ 0 (the scalar form of the kernels' steps, for its test): 2^(x log₂e) split into
/// 2ⁿ (n the nearest integer, by the 1.5 · 2²³ rounding trick, put into the
/// exponent bits) times e^g, g = (x log₂e − n) ln 2 ∈ [−0.347, 0.347], by
/// its Taylor polynomial of degree 6 (remainder below |g|⁷/7! · e^|g| ≈
/// 1.7 · 10⁻⁷). With the rounding of x log₂e (|x| · 6 · 10⁻⁸ in the
/// exponent) and of the polynomial (a few units of 2⁻²⁴), the relative
/// error is below 10⁻⁶ + |x| · 6 · 10⁻⁸; below x = −87 the result is 0
/// (eˣ < 2 · 10⁻³⁸, where f32 turns subnormal). NaN gives 0.
#[cfg(test)]
fn exp_neg(x: f32) -> f32 {
    let valid = x >= EXP_MIN;
    let x = if valid { x } else { 0.0 };
    let y = x * std::f32::consts::LOG2_E;
    let rounded = y + EXP_ROUND;
    let n = rounded - EXP_ROUND;
    let g = (y - n) * std::f32::consts::LN_2;
    let [c2, c3, c4, c5, c6] = EXP_TAYLOR;
    let p = 1.0 + g * (1.0 + g * (c2 + g * (c3 + g * (c4 + g * (c5 + g * c6)))));
    // n as an integer from the low bits of 1.5 · 2²³ + n (no float-to-int
    // conversion), then 2ⁿ by its exponent bits.
    let n = rounded.to_bits() as i32 - EXP_ROUND.to_bits() as i32;
    let scale = f32::from_bits(((n + 127) as u32) << 23);
    if valid { p * scale } else { 0.0 }
}

/// 1.5 · 2²³: adding and subtracting it rounds to the nearest integer.
const EXP_ROUND: f32 = 12_582_912.0;

/// Below this, [`exp_neg`] is 0 (eˣ < 2 · 10⁻³⁸, where f32 turns subnormal).
const EXP_MIN: f32 = -87.0;

/// The Taylor coefficients 1/k! of eᵍ, k = 2…6.
const EXP_TAYLOR: [f32; 5] = [0.5, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0, 1.0 / 720.0];

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

    /// eˣ by `exp_neg` against the library's, on a fine grid of [−87, 0]:
    /// within the documented bound 10⁻⁶ + |x| · 6 · 10⁻⁸ relative.
    #[test]
    fn exp_neg_is_within_its_bound() {
        let mut worst = 0f64;
        for i in 0..=870_000 {
            let x = -(i as f32) * 1e-4;
            let (got, want) = (exp_neg(x) as f64, (x as f64).exp());
            let rel = (got - want).abs() / want;
            worst = worst.max(rel / (1e-6 + x.abs() as f64 * 6e-8));
            assert!(rel <= 1e-6 + x.abs() as f64 * 6e-8, "e^{x}: {got} against {want}");
        }
        eprintln!("exp_neg: at most {worst:.3} of its bound");
        assert_eq!(exp_neg(-88.0), 0.0);
        assert_eq!(exp_neg(f32::NAN), 0.0);
        assert_eq!(exp_neg(0.0), 1.0);
    }

    /// The fast filter against the exact one on a real G-buffer and a noisy
    /// interleaved-like input (`office`, 61 × 37 so that rows end in a
    /// partial step): every pixel within 2 · 10⁻⁶ relative (the exponential's
    /// bound is 10⁻⁶ at the weights that matter; the normalised sum at most
    /// doubles it); the AVX2 and portable rows give the same bits.
    #[test]
    fn fast_filter_matches_the_exact_one() {
        let setup = vpl_core::SceneSetup::builtin("office").unwrap();
        let camera = setup.camera.with_resolution((61, 37)).unwrap();
        let gbuf = crate::render_gbuffer(&setup.scene, &camera);
        let mut e = Image::new(61, 37);
        let mut rng = vpl_core::rng::stream(1, 0, vpl_core::rng::Purpose::TEST, 0);
        for v in &mut e.data {
            let (a, b) = rng.next_2d();
            *v = Vec3::new(a, b, a * b) * 4.0;
        }
        for f in [CrossBilateral::default(), CrossBilateral { periods: 2, normal_power: 5, sigma: 1.5 }] {
            let (fast, exact) = (f.apply(&gbuf, &e), f.apply_exact(&gbuf, &e));
            let mut lit = 0;
            for (i, (a, b)) in fast.data.iter().zip(&exact.data).enumerate() {
                lit += (b.max_element() > 0.0) as usize;
                assert!((*a - *b).abs().max_element() <= 2e-6 * b.abs().max_element(), "pixel {i}: {a} against {b}");
            }
            assert!(lit > 1000, "{lit}");
            let mut planes = Planes::default();
            planes.fill(&f, &gbuf, &e);
            for y in 0..37 {
                let (mut a, mut b) = (vec![Vec3::ZERO; 61], vec![Vec3::ZERO; 61]);
                planes.row(f.normal_power, y, &mut a);
                lanes::row(&planes, f.normal_power, y, &mut b);
                assert_eq!(a, b, "row {y}");
            }
        }
    }
}
