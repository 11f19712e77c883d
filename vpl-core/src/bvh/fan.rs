//! Closest hits of many rays that share one origin (a shadow map's texels,
//! a pinhole camera's pixels), traced a bundle at a time.
//!
//! A bundle of up to [`FAN`] directions is bounded by a pyramid: four
//! planes through the origin, found by projecting the directions onto the
//! plane one unit along their mean (a gnomonic projection, which maps great
//! circles to lines, so the bounding rectangle of the projected points is
//! exactly a pyramid that holds every direction). The bundle walks the tree
//! once: a child is entered when its box reaches inside all four planes and
//! lies no farther from the origin than the farthest hit the bundle still
//! needs; at a leaf, each group of [`GROUP`] rays that enters its box (the
//! slab test, lane by lane) meets the leaf's triangles by the shared-origin
//! form of the watertight edge test:
//!
//! ```text
//! U = d · n₁₂,  V = d · n₂₀,  W = d · n₀₁,   nᵢⱼ = (vᵢ − o) × (vⱼ − vᵢ),
//! hit ⇔ U, V, W ≥ 0 or U, V, W ≤ 0,   t = (v₀ − o) · n_g / d · n_g,   n_g = (v₁ − v₀) × (v₂ − v₀),
//! ```
//!
//! nᵢⱼ the normal of the plane through the origin and the edge vᵢvⱼ (the
//! ray's Plücker product with the edge), n_g the triangle's normal. Each
//! edge's normal is computed from its endpoints in a fixed order and
//! negated for the other direction, so the two triangles on an edge get
//! exact negations of one value, and a ray on the edge gets U = 0 from both
//! and enters one of them: no ray slips between triangles. Writing it
//! with the edge vector vⱼ − vᵢ (exact for nearby vertices) rather than
//! (vᵢ − o) × (vⱼ − o) keeps small triangles far away accurate: the edges
//! lie within about one rounding of the distance, as in Woop et al.'s test.
//! The normals are computed once per bundle; each ray then costs four dot
//! products, and the lanes of a group run side by side (AVX2 where the CPU
//! has it).
//!
//! The hits agree with [`Bvh::closest`]'s but for rounding: t to a few
//! units in the last place, and a ray within about one rounding of an edge
//! may meet the triangle on the other side (both tests are watertight). A
//! bundle whose directions spread more than about 78° from their mean, or
//! that holds a zero or non-finite direction, is traced ray by ray with
//! [`Bvh::closest`] instead.

// The lane loops index several arrays at once, which is what lets them vectorise.
#![allow(clippy::needless_range_loop)]

use super::node::{FAR_SCALE, TINY};
use super::{BACKSTEP, Bvh, LEAF, Stack, WIDTH, leaf_range};
use crate::ray::Ray;
use glam::Vec3;

/// Rays per bundle.
pub const FAN: usize = 64;

/// Lanes of a bundle tested together against a leaf's triangles: the
/// groups none of whose rays enter the leaf's box are skipped.
const GROUP: usize = 8;

/// Cosine to the bundle's mean below which a direction sends its bundle to
/// the ray-by-ray path (about 78°): the pyramid's gnomonic projection grows
/// without bound toward 90°.
const MIN_COS: f32 = 0.2;

/// Widening of the pyramid's rectangle in the projection plane, relative
/// to its largest coordinate plus one: far more than the rounding of the
/// projection, so no direction of the bundle lies outside.
const WIDEN: f32 = 1e-4;

/// A bundle's pyramid: the inward normals of its four planes through the
/// origin, and the rounding allowance of the box test for each.
struct Pyramid {
    planes: [Vec3; 4],
    slack: [f32; 4],
}

/// The smaller of each pair, as a select (one `minps`).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The larger of each pair, as a select (one `maxps`).
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The least of [`GROUP`] lanes, halving the lanes each step (so that
/// the steps are whole-register operations).
#[inline(always)]
fn least(x: &[f32; GROUP]) -> f32 {
    let mut v = *x;
    let mut w = GROUP / 2;
    while w > 0 {
        for i in 0..w {
            v[i] = min(v[i], v[i + w]);
        }
        w /= 2;
    }
    v[0]
}

impl Pyramid {
    /// The pyramid of bundle `b`, or `None` where the bundle is too wide
    /// or a direction is zero or not finite. `extent` bounds the magnitude
    /// of every coordinate the box test subtracts (boxes and origin).
    #[inline(always)]
    fn new(b: &Bundle, extent: f32) -> Option<Pyramid> {
        let mut ok = true;
        let mut sum = [[0f32; GROUP]; 3];
        for g in &b.groups {
            for i in 0..GROUP {
                ok &= g.len[i] > 0.0 && g.len[i] < f32::INFINITY;
                let inv = 1.0 / g.len[i];
                for a in 0..3 {
                    sum[a][i] += g.d[a][i] * inv;
                }
            }
        }
        if !ok {
            return None;
        }
        let a = Vec3::from(sum.map(|s| s.iter().sum::<f32>())).try_normalize()?;
        let (b1, b2) = a.any_orthonormal_pair();
        let (mut lo, mut hi) = ([[f32::INFINITY; GROUP]; 2], [[f32::NEG_INFINITY; GROUP]; 2]);
        for g in &b.groups {
            let [dx, dy, dz] = &g.d;
            for i in 0..GROUP {
                let d = |v: Vec3| dx[i] * v.x + dy[i] * v.y + dz[i] * v.z;
                let w = d(a);
                ok &= w > MIN_COS * g.len[i];
                let rw = 1.0 / w;
                let p = [d(b1) * rw, d(b2) * rw];
                for k in 0..2 {
                    lo[k][i] = min(lo[k][i], p[k]);
                    hi[k][i] = max(hi[k][i], p[k]);
                }
            }
        }
        if !ok {
            return None;
        }
        let (x0, y0) = (least(&lo[0]), least(&lo[1]));
        let (x1, y1) = (-least(&hi[0].map(|x| -x)), -least(&hi[1].map(|x| -x)));
        let m = WIDEN * (1.0 + x0.abs().max(x1.abs()).max(y0.abs()).max(y1.abs()));
        // d · plane ≥ 0 for every d whose projection lies in the widened rectangle.
        let planes = [b1 - (x0 - m) * a, (x1 + m) * a - b1, b2 - (y0 - m) * a, (y1 + m) * a - b2];
        // A box corner's distance along a plane normal is a sum of three
        // products of differences of coordinates up to `extent`: a few
        // roundings of that size each.
        let slack = planes.map(|p| 8.0 * f32::EPSILON * extent * (p.x.abs() + p.y.abs() + p.z.abs()));
        Some(Pyramid { planes, slack })
    }
}

/// Up to [`GROUP`] rays of a bundle, lane by lane, and the best hit of each so far.
#[derive(Clone, Copy)]
struct Group {
    d: [[f32; GROUP]; 3],
    /// 1 / d per axis (components smaller than [`TINY`] taken as ±[`TINY`]).
    inv: [[f32; GROUP]; 3],
    /// Length of each direction (a box's distance from the origin is
    /// compared with t · |d|).
    len: [f32; GROUP],
    best_t: [f32; GROUP],
    best: [u32; GROUP],
}

/// A bundle: [`FAN`] / [`GROUP`] groups.
struct Bundle {
    groups: [Group; FAN / GROUP],
}

/// One triangle seen from the bundle's origin: the normals of the planes
/// through the origin and each edge, for U, V, W (edges v₁v₂, v₂v₀,
/// v₀v₁), and the triangle's own normal n_g = (v₁ − v₀) × (v₂ − v₀) with
/// e₀ · n_g, for t = e₀ · n_g / d · n_g.
struct Edges {
    n: [Vec3; 3],
    ng: Vec3,
    e0_ng: f32,
}

/// The normal of the plane through the origin `o` and the edge from `a` to
/// `b`, (a − o) × (b − a) (= (a − o) × (b − o)). The edge vector b − a is
/// exact for nearby vertices and keeps the product accurate for a small
/// triangle far away, where (a − o) × (b − o) would cancel. The product is
/// always formed from the lesser endpoint (in coordinate order) and negated
/// for the other direction, so the two triangles on an edge get exact
/// negations of one value.
#[inline(always)]
fn edge_normal(o: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let lesser = (a.x, a.y, a.z) < (b.x, b.y, b.z);
    let (p, q) = if lesser { (a, b) } else { (b, a) };
    let n = (p - o).cross(q - p);
    if lesser { n } else { -n }
}

impl Edges {
    #[inline(always)]
    fn new(o: Vec3, v: &[Vec3; 3]) -> Edges {
        let n = [edge_normal(o, v[1], v[2]), edge_normal(o, v[2], v[0]), edge_normal(o, v[0], v[1])];
        let ng = (v[1] - v[0]).cross(v[2] - v[0]);
        Edges { n, ng, e0_ng: (v[0] - o).dot(ng) }
    }

    /// Where the ray along (`dx`, `dy`, `dz`) meets the triangle: t ≥ 0,
    /// or NaN where it misses (or lies in the triangle's plane). Written
    /// for one lane; the lane loops call it, so every caller rounds alike.
    #[inline(always)]
    fn t(&self, dx: f32, dy: f32, dz: f32) -> f32 {
        let [n0, n1, n2] = self.n;
        let u = dx * n0.x + dy * n0.y + dz * n0.z;
        let v = dx * n1.x + dy * n1.y + dz * n1.z;
        let w = dx * n2.x + dy * n2.y + dz * n2.z;
        let inside = (u >= 0.0 && v >= 0.0 && w >= 0.0) | (u <= 0.0 && v <= 0.0 && w <= 0.0);
        // A ray in the triangle's plane gives ±∞ or NaN.
        let t = self.e0_ng / (dx * self.ng.x + dy * self.ng.y + dz * self.ng.z);
        if inside && (0.0..f32::INFINITY).contains(&t) { t } else { f32::NAN }
    }
}

impl Group {
    /// Whether a ray of the group enters the box (`lo`, `hi`), given
    /// relative to the origin, before its best hit (the slab test of
    /// [`BoxRay`](super::node::BoxRay), lane by lane).
    #[inline(always)]
    fn enters(&self, lo: Vec3, hi: Vec3) -> bool {
        let mut enter = [0u32; GROUP];
        for i in 0..GROUP {
            let (mut tn, mut tf) = (-BACKSTEP, self.best_t[i]);
            for a in 0..3 {
                let (t0, t1) = (lo[a] * self.inv[a][i], hi[a] * self.inv[a][i]);
                tn = max(tn, min(t0, t1));
                tf = min(tf, max(t0, t1));
            }
            enter[i] = (tn <= tf * FAR_SCALE) as u32;
        }
        enter.iter().fold(0, |m, e| m | e) != 0
    }

    /// Tests triangle `slot` against every lane, keeping nearer hits (the
    /// first of equal distances wins).
    #[inline(always)]
    fn test(&mut self, e: &Edges, slot: u32) {
        let [dx, dy, dz] = &self.d;
        for i in 0..GROUP {
            let t = e.t(dx[i], dy[i], dz[i]);
            let hit = t < self.best_t[i];
            self.best_t[i] = if hit { t } else { self.best_t[i] };
            self.best[i] = if hit { slot } else { self.best[i] };
        }
    }

    /// The farthest distance from the origin at which a lane's hit still matters.
    #[inline(always)]
    fn reach(&self) -> f32 {
        let mut r = [0f32; GROUP];
        for i in 0..GROUP {
            r[i] = -(self.best_t[i] * self.len[i]);
        }
        -least(&r)
    }
}

impl Bundle {
    /// The farthest distance from the origin at which a hit still matters,
    /// widened by more than the rounding of t and of a box's distance.
    #[inline(always)]
    fn reach(&self) -> f32 {
        self.groups.iter().fold(0f32, |r, g| r.max(g.reach())) * (1.0 + 1e-5)
    }
}

impl Bvh {
    /// The closest hit (scene triangle, t) of each ray from `o` along
    /// `dirs[i]` within `[0, t_max]`, written to `out[i]`: as
    /// [`Bvh::closest`] would find them ray by ray (the same triangles; t
    /// to rounding, see the module notes), in bundles of [`FAN`] rays that
    /// walk the tree together. Neighbouring directions should be
    /// neighbours in `dirs` (a tile of texels), so that each bundle is
    /// narrow.
    ///
    /// # Panics
    /// If `out` is shorter than `dirs`.
    pub fn closest_fan(&self, o: Vec3, dirs: &[Vec3], t_max: f32, out: &mut [Option<(u32, f32)>]) {
        assert!(out.len() >= dirs.len(), "one output per direction");
        for (dirs, out) in dirs.chunks(FAN).zip(out.chunks_mut(FAN)) {
            #[cfg(target_arch = "x86_64")]
            if self.avx2 {
                self.bundle_avx2(o, dirs, t_max, out);
                continue;
            }
            self.bundle(o, dirs, t_max, out);
        }
    }

    /// [`Bvh::bundle`] compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)] // the call of a function compiled for AVX2 and FMA, made only where the CPU has them
    fn bundle_avx2(&self, o: Vec3, dirs: &[Vec3], t_max: f32, out: &mut [Option<(u32, f32)>]) {
        #[target_feature(enable = "avx2,fma")]
        fn run(bvh: &Bvh, o: Vec3, dirs: &[Vec3], t_max: f32, out: &mut [Option<(u32, f32)>]) {
            bvh.bundle(o, dirs, t_max, out)
        }
        // SAFETY: `avx2` is set only where `is_x86_feature_detected!` found AVX2 and FMA.
        unsafe { run(self, o, dirs, t_max, out) }
    }

    /// One bundle of at most [`FAN`] rays.
    #[inline(always)]
    fn bundle(&self, o: Vec3, dirs: &[Vec3], t_max: f32, out: &mut [Option<(u32, f32)>]) {
        let ray_by_ray = |out: &mut [Option<(u32, f32)>]| {
            for (d, r) in dirs.iter().zip(out.iter_mut()) {
                *r = self.closest(&Ray { o, d: *d, t_max });
            }
        };
        if self.nodes.is_empty() || !o.is_finite() || t_max.is_nan() || t_max < 0.0 {
            return ray_by_ray(out);
        }
        // Lanes past the bundle's end repeat its first ray.
        // Hits at t = t_max count, as in `closest`: the next float up bounds them.
        let t_end = if t_max < f32::INFINITY { f32::from_bits(t_max.to_bits() + 1) } else { t_max };
        let lane =
            Group { d: [[0.0; GROUP]; 3], inv: [[0.0; GROUP]; 3], len: [0.0; GROUP], best_t: [t_end; GROUP], best: [u32::MAX; GROUP] };
        let mut b = Bundle { groups: [lane; FAN / GROUP] };
        let mut all = [dirs[0]; FAN];
        all[..dirs.len()].copy_from_slice(dirs);
        for (g, dirs) in b.groups.iter_mut().zip(all.chunks_exact(GROUP)) {
            for (i, d) in dirs.iter().enumerate() {
                for a in 0..3 {
                    g.d[a][i] = d[a];
                }
            }
            for i in 0..GROUP {
                g.len[i] = (g.d[0][i] * g.d[0][i] + g.d[1][i] * g.d[1][i] + g.d[2][i] * g.d[2][i]).sqrt();
                for a in 0..3 {
                    let x = g.d[a][i];
                    g.inv[a][i] = 1.0 / if x.abs() < TINY { TINY.copysign(x) } else { x };
                }
            }
        }
        let Some(pyramid) = Pyramid::new(&b, self.extent.max(o.abs().max_element())) else {
            return ray_by_ray(out);
        };
        let mut reach = b.reach();
        // (child, squared distance, node × WIDTH + lane of its box)
        let mut stack: Stack<(u32, f32, u32)> = Stack::new((0, 0.0, 0));
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            // Squared distance from the origin to each child's box, and
            // whether the box reaches inside every plane of the pyramid.
            let mut dist2 = [0f32; WIDTH];
            let mut inside = [true; WIDTH];
            for i in 0..WIDTH {
                let mut s = 0f32;
                for a in 0..3 {
                    let g = (n.lo[a][i] - o[a]).max(o[a] - n.hi[a][i]).max(0.0);
                    s += g * g;
                }
                dist2[i] = s;
                inside[i] = n.lo[0][i] <= n.hi[0][i];
            }
            for (p, slack) in pyramid.planes.iter().zip(pyramid.slack) {
                // The box corner farthest along the plane's normal.
                let corner = |a: usize| if p[a] >= 0.0 { &n.hi[a] } else { &n.lo[a] };
                let (cx, cy, cz) = (corner(0), corner(1), corner(2));
                for i in 0..WIDTH {
                    let s = p.x * (cx[i] - o.x) + p.y * (cy[i] - o.y) + p.z * (cz[i] - o.z);
                    inside[i] &= s >= -slack;
                }
            }
            let r2 = reach * reach;
            let entered = (0..WIDTH).filter(|&i| inside[i] && dist2[i] <= r2).map(|i| (n.child[i], dist2[i], (node * WIDTH + i) as u32));
            stack.push_nearest_last(entered, |e| e.1);
            // The next inner node; leaves on the way are tested.
            loop {
                let Some((child, d2, at)) = stack.pop() else {
                    for (i, r) in out.iter_mut().enumerate().take(dirs.len()) {
                        let (g, l) = (&b.groups[i / GROUP], i % GROUP);
                        *r = (g.best[l] != u32::MAX).then(|| (self.order[g.best[l] as usize], g.best_t[l]));
                    }
                    return;
                };
                if d2 > reach * reach {
                    continue;
                }
                if child & LEAF == 0 {
                    node = child as usize;
                    break;
                }
                let (first, count) = leaf_range(child);
                let (p, lane) = (&self.nodes[at as usize / WIDTH], at as usize % WIDTH);
                let corner = |c: &[[f32; WIDTH]; 3]| Vec3::new(c[0][lane], c[1][lane], c[2][lane]);
                let (l, h) = (corner(&p.lo) - o, corner(&p.hi) - o);
                let mut groups = 0u32;
                for (k, g) in b.groups.iter().enumerate() {
                    groups |= (g.enters(l, h) as u32) << k;
                }
                if groups == 0 {
                    continue;
                }
                for s in first..first + count {
                    let e = Edges::new(o, &self.tris[s]);
                    let mut m = groups;
                    while m != 0 {
                        let k = m.trailing_zeros() as usize;
                        m &= m - 1;
                        b.groups[k].test(&e, s as u32);
                    }
                }
                reach = b.reach();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{Purpose, stream};
    use crate::triangle::TriangleData;

    /// `n` directions around `axis` within about `spread` radians, in
    /// 8-wide rows (a tile of texels).
    fn tile(axis: Vec3, spread: f32, n: usize) -> Vec<Vec3> {
        let (b1, b2) = axis.any_orthonormal_pair();
        (0..n)
            .map(|k| {
                let (x, y) = ((k % 8) as f32 / 7.0 - 0.5, (k / 8) as f32 / 7.0 - 0.5);
                (axis + (b1 * x + b2 * y) * spread).normalize()
            })
            .collect()
    }

    /// Against every triangle tested with the same edge test, bundles
    /// find the same hits bit for bit (so the pyramid, the reach and the
    /// groups skip nothing they should not), on both traversals (AVX2 and
    /// the baseline); against `closest` ray by ray (Woop's test), the same
    /// triangle for at least 99.5 % of rays (the rest within a rounding of
    /// an edge) and, where the triangle is the same, t within 10⁻⁵ relative
    /// plus 16 roundings of the scene's largest coordinate.
    #[test]
    fn bundles_find_what_testing_every_triangle_finds() {
        let setup = crate::SceneSetup::builtin("office").unwrap();
        let scene = &setup.scene;
        let tris: Vec<[Vec3; 3]> = scene.geometry.triangles.iter().map(TriangleData::corners).collect();
        let bvh = Bvh::build(&tris).unwrap();
        let baseline = Bvh { avx2: false, ..Bvh::build(&tris).unwrap() };
        let (lo, hi) = scene.geometry.bounds;
        // Both tests subtract coordinates of this size: t is exact to a
        // few roundings of it, plus a few of its own.
        let extent = lo.abs().max(hi.abs()).max_element();
        let mut rng = stream(7, 0, Purpose::TEST, 0);
        let (mut rays, mut same, mut hits) = (0usize, 0usize, 0usize);
        for b in 0..300 {
            let (u, v) = rng.next_2d();
            let o = lo + (hi - lo) * Vec3::new(u, v, rng.next_f32());
            let (u, v) = rng.next_2d();
            let axis = crate::sampling::uniform_sphere(u, v);
            // Narrow and wide tiles, full and partial bundles, segments.
            let spread = [0.02, 0.2, 1.0][b % 3];
            let n = if b % 5 == 0 { 37 } else { FAN };
            let dirs = tile(axis, spread, n);
            let t_max = if b % 4 == 0 { 2.0 } else { f32::INFINITY };
            let mut got = vec![None; n];
            bvh.closest_fan(o, &dirs, t_max, &mut got);
            let mut base = vec![None; n];
            baseline.closest_fan(o, &dirs, t_max, &mut base);
            assert_eq!(got, base, "bundle {b}: AVX2 and baseline");
            for (i, d) in dirs.iter().enumerate() {
                let brute = tris
                    .iter()
                    .enumerate()
                    .filter_map(|(k, v)| Some((k as u32, Edges::new(o, v).t(d.x, d.y, d.z))).filter(|h| h.1 <= t_max))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                assert_eq!(got[i].map(|h| h.1), brute.map(|h| h.1), "bundle {b} ray {i}");
                let ray = bvh.closest(&Ray { o, d: *d, t_max });
                rays += 1;
                hits += ray.is_some() as usize;
                match (got[i], ray) {
                    (Some((a, ta)), Some((b, tb))) if a == b => {
                        assert!((ta - tb).abs() <= 1e-5 * tb + 16.0 * f32::EPSILON * extent, "bundle {b} ray {i}: {ta} against {tb}");
                        same += 1;
                    }
                    (None, None) => same += 1,
                    _ => {}
                }
            }
        }
        assert!(hits > rays / 2, "{hits} of {rays}");
        assert!(same as f64 >= 0.995 * rays as f64, "{same} of {rays} rays agree");
    }

    /// Rays aimed at points on the shared edges of a fan of eight
    /// triangles (and at its centre vertex), 64 at a time from one origin,
    /// all hit it.
    #[test]
    fn no_ray_of_a_bundle_slips_between_triangles() {
        let (centre, ring, fan) = super::super::watertight::shared_edge_fan();
        let bvh = Bvh::build(&fan).unwrap();
        let mut rng = stream(5, 0, Purpose::TEST, 1);
        for b in 0..320 {
            let (u, v) = rng.next_2d();
            let o = centre + Vec3::new(u - 0.5, v - 0.5, 1.0 + u) * 3.0;
            let dirs: Vec<Vec3> = (0..FAN)
                .map(|n| {
                    let f = if n == 0 { 0.0 } else { rng.next_f32() };
                    centre + (ring[n % 8] - centre) * f - o
                })
                .collect();
            let mut got = vec![None; FAN];
            bvh.closest_fan(o, &dirs, f32::INFINITY, &mut got);
            assert!(got.iter().all(Option::is_some), "bundle {b}: {:?}", got.iter().position(Option::is_none));
        }
    }

    /// A bundle with a zero or non-finite direction, or one spread over
    /// the whole sphere, is traced ray by ray: the same answers as
    /// `closest`, bit for bit; an empty tree hits nothing.
    #[test]
    fn odd_bundles_go_ray_by_ray() {
        let setup = crate::SceneSetup::builtin("cornell").unwrap();
        let bvh = &setup.scene.geometry.bvh;
        let o = Vec3::new(0.1, 0.2, 0.3);
        let mut wide = tile(Vec3::Y, 0.05, 16);
        wide.extend(tile(-Vec3::Y, 0.05, 16));
        let mut broken = tile(Vec3::X, 0.05, 16);
        broken[3] = Vec3::ZERO;
        broken[5] = Vec3::new(f32::NAN, 0.0, 1.0);
        for dirs in [wide, broken] {
            let mut got = vec![None; dirs.len()];
            bvh.closest_fan(o, &dirs, f32::INFINITY, &mut got);
            let want: Vec<_> = dirs.iter().map(|d| bvh.closest(&Ray::new(o, *d))).collect();
            assert_eq!(got, want);
        }
        let mut got = [Some((0, 0.0))];
        Bvh::build(&[]).unwrap().closest_fan(o, &[Vec3::Y], f32::INFINITY, &mut got);
        assert_eq!(got, [None]);
    }
}
