//! The k-nearest-neighbour density estimator of eq. (7).

use crate::accepted::AcceptTree;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::num::NonZero;
use std::sync::OnceLock;

/// Errors of [`KnnDensity`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum DensityError {
    /// A point has a NaN or infinite coordinate.
    #[error("point {0} has a non-finite coordinate")]
    NonFinite(usize),
    /// k must be at least 1.
    #[error("k must be at least 1")]
    ZeroK,
    /// There are fewer points than the query needs neighbours.
    #[error("{needed} neighbours asked of a set of {points} points")]
    TooFewPoints {
        /// Neighbours the query needs.
        needed: usize,
        /// Points in the set.
        points: usize,
    },
}

/// `k = max(1, ⌊√(I/32)⌋)`, the neighbour count for the densities of
/// rendered VPLs (eq. 8): consistent, since k → ∞ and k/I → 0 as I grows.
pub fn rendering_k(budget: usize) -> usize {
    (((budget as f64) / 32.0).sqrt().floor() as usize).max(1)
}

/// A point set with a k-d tree over it, answering eq. (7).
pub struct KnnDensity {
    points: Vec<[f32; 3]>,
    /// The k-th-neighbour tree (kiddo), built by the first such query: a
    /// set asked only for nearest accepted points, members' nearest or
    /// balls (SMC's candidate hits) never builds it.
    tree: OnceLock<Option<ImmutableKdTree<f32, 3>>>,
    /// The tree of predicate queries, built by the first of them.
    accepted: OnceLock<AcceptTree>,
}

impl std::fmt::Debug for KnnDensity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KnnDensity").field("points", &self.points.len()).finish()
    }
}

impl KnnDensity {
    /// Builds the tree over `points` (an empty set is allowed; its queries fail).
    pub fn new(points: &[Vec3]) -> Result<KnnDensity, DensityError> {
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(DensityError::NonFinite(i));
        }
        let points: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
        Ok(KnnDensity { points, tree: OnceLock::new(), accepted: OnceLock::new() })
    }

    /// The k-th-neighbour tree, `None` for an empty set.
    fn kd_tree(&self) -> Option<&ImmutableKdTree<f32, 3>> {
        // Only fails on an empty slice.
        self.tree.get_or_init(|| if self.points.is_empty() { None } else { ImmutableKdTree::new_from_slice(&self.points).ok() }).as_ref()
    }

    /// Number of points N.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Squared distance from `q` to its `k`-th nearest point of the set.
    pub fn radius_sq(&self, q: Vec3, k: usize) -> Result<f32, DensityError> {
        let k = NonZero::new(k).ok_or(DensityError::ZeroK)?;
        if k.get() > self.points.len() {
            return Err(DensityError::TooFewPoints { needed: k.get(), points: self.points.len() });
        }
        Ok(self.kth(&q.to_array(), k))
    }

    fn kth(&self, q: &[f32; 3], k: NonZero<usize>) -> f32 {
        let tree = self.kd_tree().expect("a non-empty set has a tree");
        if k.get() == 1 {
            return tree.query(q).nearest_one::<SquaredEuclidean<f32>>().execute().distance;
        }
        let r = tree.query(q).nearest_n::<SquaredEuclidean<f32>>(k).execute();
        r.last().map_or(f32::INFINITY, |n| n.distance)
    }

    /// Density of the set at `q` from its `k` nearest points:
    /// `k / (N π r_k²)` (eq. 7). Infinite when `q` sits on k points.
    pub fn at(&self, q: Vec3, k: usize) -> Result<f32, DensityError> {
        let r2 = self.radius_sq(q, k)?;
        Ok(density(k, self.points.len(), r2))
    }

    /// [`KnnDensity::at`] for many points, in parallel; an empty set or too
    /// large a `k` gives an error.
    pub fn at_many(&self, qs: &[Vec3], k: usize) -> Result<Vec<f32>, DensityError> {
        let kk = NonZero::new(k).ok_or(DensityError::ZeroK)?;
        if k > self.points.len() {
            return Err(DensityError::TooFewPoints { needed: k, points: self.points.len() });
        }
        let n = self.points.len();
        Ok(qs.par_iter().map(|q| density(k, n, self.kth(&q.to_array(), kk))).collect())
    }

    /// Squared distance from every point of the set to its `k`-th nearest
    /// *other* point (the point itself is not its own neighbour), in the
    /// order the points were given. A set of at most `k` points gives
    /// infinite radii (no k-th neighbour exists). One walk per leaf of
    /// the predicate tree answers for all of the leaf's points
    /// (`accepted.rs`); the radii equal those of a k + 1 nearest search
    /// from each point ([`KnnDensity::radius_sq`]), itself included.
    pub fn member_radii_sq(&self, k: usize) -> Vec<f32> {
        let n = self.points.len();
        if k == 0 || k >= n {
            return vec![if k == 0 { 0.0 } else { f32::INFINITY }; n];
        }
        self.accepted().members_kth(k)
    }

    /// The nearest point of the set to `q` that `accept` takes (by index),
    /// other than `skip`, as (index, squared distance), among its 512
    /// nearest; `None` when none of those is accepted
    /// ([`KnnDensity::nearest_accepted_n`]).
    pub fn nearest_accepted(&self, q: Vec3, skip: Option<usize>, accept: impl Fn(usize) -> bool) -> Option<(usize, f32)> {
        self.nearest_accepted_n(q, skip, accept, 1).into_iter().next()
    }

    /// Up to `m` nearest points of the set to `q` that `accept` takes,
    /// other than `skip`, nearest first, among its 512 nearest (`skip`
    /// counted among them; a point tied with the 512th distance too). Ties
    /// in distance go to the lower index. The first call builds a second
    /// tree that skips what `accept` refuses instead of ranking it (see
    /// `accepted.rs`).
    pub fn nearest_accepted_n(&self, q: Vec3, skip: Option<usize>, accept: impl Fn(usize) -> bool, m: usize) -> Vec<(usize, f32)> {
        if m == 0 || self.points.is_empty() {
            return Vec::new();
        }
        self.accepted().nearest_accepted(&q.to_array(), skip, accept, m, ACCEPT_AMONG.min(self.points.len()))
    }

    /// [`KnnDensity::nearest_accepted_n`], and how far it looks from `q`
    /// ([`KnnDensity::accept_reach_sq`]) when the search had to find that
    /// (a predicate that few of the 512 nearest points pass).
    pub fn nearest_accepted_n_reach(
        &self,
        q: Vec3,
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
    ) -> (Vec<(usize, f32)>, Option<f32>) {
        if m == 0 || self.points.is_empty() {
            return (Vec::new(), None);
        }
        self.accepted().nearest_accepted_reach(&q.to_array(), skip, accept, m, ACCEPT_AMONG.min(self.points.len()))
    }

    /// How far [`KnnDensity::nearest_accepted_n`] looks from `q`: the
    /// squared distance of its 512th nearest point of the set (infinite
    /// for an empty set; the farthest point's for a set of at most 512).
    /// A query asked again with other predicates finds it once and hands
    /// it to [`KnnDensity::nearest_accepted_n_within`].
    pub fn accept_reach_sq(&self, q: Vec3) -> f32 {
        if self.points.is_empty() {
            return f32::INFINITY;
        }
        self.accepted().reach_sq(&q.to_array(), ACCEPT_AMONG.min(self.points.len()))
    }

    /// [`KnnDensity::nearest_accepted_n`]'s answer, given its reach
    /// `reach_sq` from [`KnnDensity::accept_reach_sq`] (`q`) or from an
    /// earlier [`KnnDensity::nearest_accepted_n_reach`] at `q`: one walk
    /// within that distance instead of one that may reach the 512th
    /// point, give up and walk again (what a predicate that few points
    /// near `q` pass costs). Ties at the reach count as within it, as they
    /// do there.
    pub fn nearest_accepted_n_within(
        &self,
        q: Vec3,
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
        reach_sq: f32,
    ) -> Vec<(usize, f32)> {
        if m == 0 || self.points.is_empty() {
            return Vec::new();
        }
        self.accepted().nearest_accepted_within(&q.to_array(), skip, accept, m, reach_sq)
    }

    /// For each of `queries` (finite), the nearest point of the set that
    /// `accept(query, point)` takes, as [`KnnDensity::nearest_accepted`]
    /// answers it with no point skipped, for all the queries at once: the
    /// queries near one another walk the tree together (see `accepted.rs`):
    /// 10,700 probes among 2,048 VPLs took 1.4 ms against 2.2 ms for one
    /// walk each, both on 2 threads (`benches/neighbours.rs`).
    pub fn nearest_accepted_each(&self, queries: &[Vec3], accept: impl Fn(usize, usize) -> bool + Sync) -> Vec<Option<(usize, f32)>> {
        if self.points.is_empty() {
            return vec![None; queries.len()];
        }
        let qs: Vec<[f32; 3]> = queries.iter().map(|q| q.to_array()).collect();
        self.accepted().nearest_accepted_each(&qs, &accept, ACCEPT_AMONG.min(self.points.len()))
    }

    /// [`KnnDensity::nearest_accepted_each`] for every point of `queries`,
    /// in their order: a set whose tree is built (or kept) already walks
    /// as the queries' tree, and none is built for them.
    pub fn nearest_accepted_each_of(
        &self,
        queries: &KnnDensity,
        accept: impl Fn(usize, usize) -> bool + Sync,
    ) -> Vec<Option<(usize, f32)>> {
        if self.points.is_empty() {
            return vec![None; queries.len()];
        }
        self.accepted().nearest_accepted_each_of(queries.accepted(), &accept, ACCEPT_AMONG.min(self.points.len()))
    }

    /// Every point of the set within squared distance `r2` of `q`, as
    /// (index, squared distance), in no particular order.
    pub fn within(&self, q: Vec3, r2: f32) -> Vec<(usize, f32)> {
        if self.points.is_empty() || r2.is_nan() || r2 < 0.0 {
            return Vec::new();
        }
        self.accepted().within(&q.to_array(), r2)
    }

    /// The nearest *other* point of every point of the set, as (index,
    /// squared distance), in the order the points were given (ties in
    /// distance to the lower index); `None` for a set of one point.
    pub fn member_nearest(&self) -> Vec<Option<(usize, f32)>> {
        let n = self.points.len();
        if n < 2 {
            return vec![None; n];
        }
        self.accepted().members_nearest()
    }

    /// The set with the tree of its neighbour and predicate queries built
    /// now (in parallel), which the first such query builds otherwise:
    /// where threads share the set, that query's thread builds it alone
    /// while the others wait on it.
    pub fn prepared(self) -> KnnDensity {
        if !self.points.is_empty() {
            self.accepted();
        }
        self
    }

    /// The k-d tree of the predicate queries, built on first use.
    fn accepted(&self) -> &AcceptTree {
        self.accepted.get_or_init(|| AcceptTree::new(&self.points))
    }

    /// Density at every point of the set from its `k` nearest other points,
    /// `k / (N π r_k²)`; zero for a set too small to have k other points.
    pub fn members(&self, k: usize) -> Vec<f32> {
        let n = self.points.len();
        self.member_radii_sq(k).into_iter().map(|r2| density(k, n, r2)).collect()
    }
}

/// The densities of a VPL set, each point against the others (eq. 7 with
/// the point excluded), in the order given: k is lowered to n − 1 for a set
/// too small for it, and a single point (or k = 0) gets the uniform density
/// 1 / `area` over the scene's surface. Non-finite points give zeros.
pub fn set_densities(points: &[Vec3], k: usize, area: f32) -> Vec<f32> {
    let n = points.len();
    let k = k.min(n.saturating_sub(1));
    if k == 0 {
        return vec![1.0 / area.max(f32::MIN_POSITIVE); n];
    }
    KnnDensity::new(points).map(|d| d.members(k)).unwrap_or_else(|_| vec![0.0; n])
}

/// How many of a query's nearest points the predicate queries look among.
const ACCEPT_AMONG: usize = 512;

/// `k / (n π r²)`: infinite at r = 0, zero at r = ∞.
#[inline]
fn density(k: usize, n: usize, r2: f32) -> f32 {
    k as f32 / (n as f32 * PI * r2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_densities_fall_back_for_small_sets() {
        assert!(set_densities(&[], 8, 2.0).is_empty());
        assert_eq!(set_densities(&[Vec3::ZERO], 8, 2.0), vec![0.5]);
        // Two points 1 apart: k lowered to 1, density 1 / (2 π · 1²) each.
        let d = set_densities(&[Vec3::ZERO, Vec3::X], 8, 2.0);
        assert!(d.iter().all(|&p| (p - 1.0 / (2.0 * PI)).abs() < 1e-6), "{d:?}");
        assert_eq!(set_densities(&[Vec3::ZERO, Vec3::splat(f32::NAN)], 1, 2.0), vec![0.0, 0.0]);
    }

    #[test]
    fn rendering_k_follows_eq_8() {
        assert_eq!(rendering_k(1), 1);
        assert_eq!(rendering_k(32), 1);
        assert_eq!(rendering_k(128), 2);
        assert_eq!(rendering_k(2048), 8);
        assert_eq!(rendering_k(8192), 16);
        assert_eq!(rendering_k(40_000), 35);
    }

    #[test]
    fn distances_on_a_line() {
        let pts: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let d = KnnDensity::new(&pts).unwrap();
        assert_eq!(d.radius_sq(Vec3::new(0.2, 0.0, 0.0), 1).unwrap(), 0.2f32 * 0.2);
        assert_eq!(d.radius_sq(Vec3::new(0.2, 0.0, 0.0), 3).unwrap(), 1.8f32 * 1.8);
        // Members exclude themselves: the end point's 2nd neighbour is 2 away.
        let r = d.member_radii_sq(2);
        assert_eq!(r, vec![4.0, 1.0, 1.0, 1.0, 4.0]);
        let p = d.members(1);
        assert!((p[2] - 1.0 / (5.0 * PI)).abs() < 1e-7);
        assert!(d.member_radii_sq(5).iter().all(|r| r.is_infinite()));
        assert_eq!(d.member_nearest()[4], Some((3, 1.0)));
        assert_eq!(KnnDensity::new(&[Vec3::ZERO]).unwrap().member_nearest(), vec![None]);
        let mut w = d.within(Vec3::new(2.0, 0.0, 0.0), 1.0);
        w.sort_by_key(|x| x.0);
        assert_eq!(w, vec![(1, 1.0), (2, 0.0), (3, 1.0)]);
        assert_eq!(d.nearest_accepted(Vec3::ZERO, Some(0), |j| j % 2 == 0), Some((2, 4.0)));
        assert_eq!(d.nearest_accepted(Vec3::ZERO, None, |j| j > 9), None);
        assert_eq!(d.nearest_accepted_n(Vec3::ZERO, None, |j| j != 1, 3), vec![(0, 0.0), (2, 4.0), (3, 9.0)]);
        assert_eq!(d.members(5), vec![0.0; 5]);
    }

    /// Every member's k-th radius is the (k + 1)-th of a search from it,
    /// itself included, bit for bit: random clouds, a plane, and points
    /// repeated (distance 0 to another member), for several k.
    #[test]
    fn member_radii_are_those_of_a_search_from_each_member() {
        let mut rng = vpl_core::rng::stream(3, 0, vpl_core::rng::Purpose::TEST, 0);
        for (case, n) in [(0, 3000), (1, 700), (2, 64), (3, 17)] {
            let mut pts: Vec<Vec3> = (0..n)
                .map(|_| {
                    let (a, b) = rng.next_2d();
                    Vec3::new(a * 10.0, if case == 1 { 2.0 } else { rng.next_f32() * 3.0 }, b * 4.0)
                })
                .collect();
            for i in (0..n).step_by(7) {
                pts[i] = pts[i / 2];
            }
            let d = KnnDensity::new(&pts).unwrap();
            for k in [1, 2, 8, 16] {
                let radii = d.member_radii_sq(k);
                for (i, p) in pts.iter().enumerate() {
                    let want = if k < n { d.radius_sq(*p, k + 1).unwrap() } else { f32::INFINITY };
                    assert_eq!(radii[i].to_bits(), want.to_bits(), "case {case}, k {k}, point {i}");
                }
            }
        }
    }

    /// The queries given as a set of their own (its tree built, as a
    /// caller that keeps one has it) get the answers the list of their
    /// points gets, in the same order; an empty set of queries, none.
    #[test]
    fn queries_as_a_set_answer_as_their_points() {
        let mut rng = vpl_core::rng::stream(4, 0, vpl_core::rng::Purpose::TEST, 0);
        let mut cloud =
            |n: usize| -> Vec<Vec3> { (0..n).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 5.0).collect() };
        let sites = KnnDensity::new(&cloud(600)).unwrap();
        let queries = cloud(1500);
        let set = KnnDensity::new(&queries).unwrap();
        set.member_nearest();
        let accept = |q: usize, i: usize| (q + i) % 3 != 0;
        assert_eq!(sites.nearest_accepted_each_of(&set, accept), sites.nearest_accepted_each(&queries, accept));
        assert!(sites.nearest_accepted_each_of(&KnnDensity::new(&[]).unwrap(), accept).is_empty());
        assert_eq!(KnnDensity::new(&[]).unwrap().nearest_accepted_each_of(&set, accept), vec![None; 1500]);
        // A set prepared ahead answers as one that builds its tree on first use.
        let prepared = KnnDensity::new(&queries).unwrap().prepared();
        assert_eq!(prepared.member_nearest(), KnnDensity::new(&queries).unwrap().member_nearest());
        assert!(KnnDensity::new(&[]).unwrap().prepared().is_empty());
    }

    #[test]
    fn errors_are_typed() {
        assert_eq!(KnnDensity::new(&[Vec3::NAN]).unwrap_err(), DensityError::NonFinite(0));
        let d = KnnDensity::new(&[Vec3::ZERO]).unwrap();
        assert_eq!(d.at(Vec3::ONE, 0).unwrap_err(), DensityError::ZeroK);
        assert_eq!(d.at(Vec3::ONE, 2).unwrap_err(), DensityError::TooFewPoints { needed: 2, points: 1 });
        let e = KnnDensity::new(&[]).unwrap();
        assert!(e.is_empty() && e.at(Vec3::ONE, 1).is_err() && e.at_many(&[Vec3::ONE], 1).is_err());
        assert!(e.members(1).is_empty());
    }
}
