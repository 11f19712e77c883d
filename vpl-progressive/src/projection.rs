//! Projection maps (§5.3.1): per VPL, the directions in which a photon may
//! first meet a specular surface, so that caustic photons are aimed there
//! only.
//!
//! A map covers the whole sphere of directions around the VPL in
//! `rows × cols` cells of equal θ (polar angle from world +Z) and φ
//! (azimuth) steps. Every specular triangle is splatted conservatively: the
//! cone around its bounding sphere, as seen from the VPL, marks every cell
//! that its θ band and φ range touch (the paper splats the bounding box of
//! the projected vertices; a bounding cone cannot miss a triangle whose
//! edges bulge between its vertices, near a pole or across the φ seam).
//! Photons then draw directions uniformly by solid angle over the marked
//! cells, with density 1/Ω_marked, and carry that density in their weight:
//! the estimate is unbiased because every direction outside the map first
//! meets a diffuse surface, where a caustic photon is discarded anyway.

use std::f32::consts::{PI, TAU};
use vpl_core::glam::Vec3;

/// A bounding sphere of a specular triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularBound {
    /// Centre.
    pub c: Vec3,
    /// Radius.
    pub r: f32,
}

/// The specular triangles' bounds, grouped into clusters of consecutive
/// triangles (neighbours on a mesh) with a bounding sphere each: a cluster
/// seen under a small angle is splatted as one cone, a near one triangle by
/// triangle. Both are conservative.
#[derive(Clone, Debug, Default)]
pub struct SpecularSet {
    /// Every specular triangle's bound.
    pub triangles: Vec<SpecularBound>,
    /// (bound of the cluster, its triangles' range in `triangles`).
    pub clusters: Vec<(SpecularBound, std::ops::Range<usize>)>,
}

/// Triangles per cluster.
const CLUSTER: usize = 16;

impl SpecularSet {
    /// Clusters `triangles` in runs of consecutive bounds.
    pub fn new(triangles: Vec<SpecularBound>) -> SpecularSet {
        let clusters = (0..triangles.len())
            .step_by(CLUSTER)
            .map(|i| {
                let range = i..(i + CLUSTER).min(triangles.len());
                let ts = &triangles[range.clone()];
                let c = ts.iter().map(|t| t.c).sum::<Vec3>() / ts.len() as f32;
                let r = ts.iter().map(|t| (t.c - c).length() + t.r).fold(0.0f32, f32::max);
                (SpecularBound { c, r }, range)
            })
            .collect();
        SpecularSet { triangles, clusters }
    }

    /// Whether there is no specular triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// The marked cells of one VPL's projection map, ready for sampling.
#[derive(Clone, Debug, Default)]
pub struct ProjectionMap {
    rows: usize,
    cols: usize,
    marked: Vec<bool>,
    /// Marked cell indices.
    cells: Vec<u32>,
    /// Cumulative solid angle over `cells`.
    cdf: Vec<f32>,
}

/// Angular margin added to every cone (radians), against rounding.
const MARGIN: f32 = 1e-3;

impl ProjectionMap {
    /// The map of a VPL at `y` for the specular triangles of `set`. With a
    /// `hemisphere` normal, bounds wholly behind the plane through `y` are
    /// skipped (the VPL cannot emit there).
    pub fn build(y: Vec3, hemisphere: Option<Vec3>, set: &SpecularSet, size: (usize, usize)) -> ProjectionMap {
        let (rows, cols) = size;
        let mut map = ProjectionMap { rows, cols, marked: vec![false; rows * cols], cells: Vec::new(), cdf: Vec::new() };
        // A cluster narrower than this many cell heights is splatted whole.
        let small = 2.0 * PI / rows as f32;
        'clusters: for (cb, range) in &set.clusters {
            if hemisphere.is_some_and(|n| (cb.c - y).dot(n) < -cb.r) {
                continue;
            }
            let dist = (cb.c - y).length();
            if dist > cb.r * 1.0001 + 1e-6 && (cb.r / dist).asin() < small {
                if !map.splat(y, cb) {
                    break;
                }
                continue;
            }
            for b in &set.triangles[range.clone()] {
                if hemisphere.is_some_and(|n| (b.c - y).dot(n) < -b.r) {
                    continue;
                }
                if !map.splat(y, b) {
                    break 'clusters;
                }
            }
        }
        let dtheta = PI / rows as f32;
        let dphi = TAU / cols as f32;
        let mut acc = 0.0f32;
        for r in 0..rows {
            let omega = ((r as f32 * dtheta).cos() - ((r + 1) as f32 * dtheta).cos()) * dphi;
            for c in 0..cols {
                if map.marked[r * cols + c] {
                    acc += omega;
                    map.cells.push((r * cols + c) as u32);
                    map.cdf.push(acc);
                }
            }
        }
        map
    }

    /// Marks the cone of bound `b` seen from `y`; `false` when `y` lies
    /// inside it and every cell has been marked.
    fn splat(&mut self, y: Vec3, b: &SpecularBound) -> bool {
        let d = b.c - y;
        let dist = d.length();
        if dist <= b.r * 1.0001 + 1e-6 {
            self.marked.iter_mut().for_each(|m| *m = true);
            return false;
        }
        let alpha = (b.r / dist).asin() + MARGIN;
        self.mark_cone(d / dist, alpha);
        true
    }

    /// Marks the cells a cone around unit `axis` with half-angle `alpha` touches.
    fn mark_cone(&mut self, axis: Vec3, alpha: f32) {
        let (rows, cols) = (self.rows, self.cols);
        let theta = axis.z.clamp(-1.0, 1.0).acos();
        let phi = axis.y.atan2(axis.x).rem_euclid(TAU);
        let dtheta = PI / rows as f32;
        let dphi = TAU / cols as f32;
        let t0 = theta - alpha;
        let t1 = theta + alpha;
        let r0 = (t0.max(0.0) / dtheta).floor() as usize;
        let r1 = ((t1.min(PI) / dtheta).floor() as usize).min(rows - 1);
        // A cone that reaches a pole spans every φ; otherwise α < min(θ, π − θ)
        // and its azimuths lie within asin(sin α / sin θ) of φ.
        let all_phi = t0 <= 0.0 || t1 >= PI;
        let span = if all_phi { PI } else { (alpha.sin() / theta.sin()).min(1.0).asin() };
        for r in r0..=r1 {
            if span >= PI * 0.999 {
                for c in 0..cols {
                    self.marked[r * cols + c] = true;
                }
                continue;
            }
            let c0 = ((phi - span) / dphi).floor() as i64;
            let c1 = ((phi + span) / dphi).floor() as i64;
            for c in c0..=c1 {
                let c = c.rem_euclid(cols as i64) as usize;
                self.marked[r * cols + c] = true;
            }
        }
    }

    /// Whether no cell is marked (the VPL sees no specular surface).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Solid angle of the marked cells (sr).
    pub fn solid_angle(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Fraction of the sphere marked.
    pub fn coverage(&self) -> f32 {
        self.solid_angle() / (4.0 * PI)
    }

    /// Whether direction `w` falls in a marked cell.
    pub fn contains(&self, w: Vec3) -> bool {
        self.marked.get(self.cell_of(w)).copied().unwrap_or(false)
    }

    fn cell_of(&self, w: Vec3) -> usize {
        let theta = w.z.clamp(-1.0, 1.0).acos();
        let phi = w.y.atan2(w.x).rem_euclid(TAU);
        let r = ((theta / PI * self.rows as f32) as usize).min(self.rows - 1);
        let c = ((phi / TAU * self.cols as f32) as usize).min(self.cols - 1);
        r * self.cols + c
    }

    /// A direction drawn uniformly by solid angle over the marked cells with
    /// `u` ∈ [0, 1)³, and its density 1/Ω_marked. `None` for an empty map.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    pub fn sample(&self, u: f32, v: (f32, f32)) -> Option<(Vec3, f32)> {
        let total = self.solid_angle();
        if !(total > 0.0) {
            return None;
        }
        let target = u * total;
        let i = self.cdf.partition_point(|&c| c <= target).min(self.cells.len() - 1);
        let cell = self.cells[i] as usize;
        let (r, c) = (cell / self.cols, cell % self.cols);
        let dtheta = PI / self.rows as f32;
        let dphi = TAU / self.cols as f32;
        let (z0, z1) = ((r as f32 * dtheta).cos(), ((r + 1) as f32 * dtheta).cos());
        let z = z0 + (z1 - z0) * v.0;
        let phi = (c as f32 + v.1) * dphi;
        let s = (1.0 - z * z).max(0.0).sqrt();
        Some((Vec3::new(s * phi.cos(), s * phi.sin(), z), 1.0 / total))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::rng::{Purpose, stream};
    use vpl_core::sampling::uniform_sphere;

    /// Every direction that meets a bounding sphere lies in a marked cell,
    /// for spheres near the poles, across the seam and close to the VPL.
    #[test]
    fn cones_are_conservative() {
        let mut rng = stream(9, 0, Purpose::TEST, 0);
        for case in 0..200 {
            let c = uniform_sphere(rng.next_f32(), rng.next_f32()) * (0.3 + 3.0 * rng.next_f32());
            let r = 0.02 + 0.5 * rng.next_f32();
            let b = SpecularBound { c, r };
            let map = ProjectionMap::build(Vec3::ZERO, None, &SpecularSet::new(vec![b]), (128, 256));
            for _ in 0..2000 {
                // A direction toward a random point of the sphere.
                let q = c + uniform_sphere(rng.next_f32(), rng.next_f32()) * (r * rng.next_f32().sqrt());
                let w = q.normalize();
                assert!(map.contains(w), "case {case}: {w} toward {c} r {r} not marked");
            }
        }
    }

    /// Sampled directions are uniform over the marked cells: the mean of
    /// 1/pdf estimates the marked solid angle, and samples stay inside.
    #[test]
    fn samples_stay_in_marked_cells() {
        let b = [SpecularBound { c: Vec3::new(1.0, 2.0, 0.5), r: 0.4 }, SpecularBound { c: Vec3::new(0.0, 0.0, -2.0), r: 0.3 }];
        let map = ProjectionMap::build(Vec3::ZERO, None, &SpecularSet::new(b.to_vec()), (128, 256));
        let mut rng = stream(9, 0, Purpose::TEST, 1);
        for _ in 0..10_000 {
            // Away from cell borders, where rounding may name the neighbour.
            let v = rng.next_2d();
            let (w, pdf) = map.sample(rng.next_f32(), (0.001 + 0.998 * v.0, 0.001 + 0.998 * v.1)).unwrap();
            assert!(map.contains(w), "{w}");
            assert!((pdf * map.solid_angle() - 1.0).abs() < 1e-5);
        }
        // Coverage is small but at least the cones' solid angle.
        let cone = |r: f32, d: f32| TAU * (1.0 - (1.0 - (r / d).powi(2)).sqrt());
        let exact = cone(0.4, b[0].c.length()) + cone(0.3, 2.0);
        assert!(map.solid_angle() >= exact && map.solid_angle() < 3.0 * exact, "{} vs {exact}", map.solid_angle());
    }

    #[test]
    fn hemisphere_skips_bounds_behind() {
        let b = SpecularSet::new(vec![SpecularBound { c: Vec3::new(0.0, 0.0, -2.0), r: 0.3 }]);
        assert!(ProjectionMap::build(Vec3::ZERO, Some(Vec3::Z), &b, (128, 256)).is_empty());
        assert!(!ProjectionMap::build(Vec3::ZERO, Some(-Vec3::Z), &b, (128, 256)).is_empty());
    }
}
