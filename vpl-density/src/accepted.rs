//! Nearest neighbours that a predicate accepts, found by a search that
//! skips what the predicate refuses instead of ranking it.
//!
//! [`crate::KnnDensity::nearest_accepted_n`] answers: the first `m` points,
//! in order of distance, that `accept` takes among the `K` = min(512, N)
//! nearest points of the set. Asking a plain k-d tree for the 2m, 16m,
//! 64m and then 512 nearest and filtering them costs a sorted list of up to
//! 512 points whenever the accepted ones are rare (a probe on a floor whose
//! nearest VPLs sit on the wall beside it), and that was most of an SMC
//! frame's time.
//!
//! This tree (median splits on the widest axis, boxes per node, leaves of
//! [`LEAF`] points) is walked depth first, nearer child first, keeping only
//! the `m` best accepted points. Two bounds skip a node:
//!
//! - **The m-th accepted point.** A node whose box lies beyond the m-th best
//!   accepted distance holds nothing better.
//! - **The K nearest.** Most walks end before they have seen K points, and
//!   then every point they return ranks below K. A walk that reaches K
//!   points starts again keeping the K smallest distances it sees (a max
//!   heap); a node whose box lies beyond the K-th of them holds only points
//!   that rank K or later, and an accepted point beyond it is dropped at the
//!   end. Either way, every point nearer than a returned one has been seen,
//!   so the answer is the one of the rounds above: the first m accepted of
//!   the K nearest (a point tied with the K-th distance counts as among
//!   them).
//!
//! Ties in distance go to the lower index, so the answer depends only on
//! the points and their order, never on the thread that asks.

use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Points per leaf.
pub(crate) const LEAF: usize = 8;

/// One node: its box and either its children or its points.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    /// Children (`left`, `left + 1`) when `count == 0`, else the first of
    /// `count` points in the tree's order.
    first: u32,
    count: u32,
}

/// A k-d tree for [`AcceptTree::nearest_accepted`].
#[derive(Clone, Debug)]
pub(crate) struct AcceptTree {
    nodes: Vec<Node>,
    /// The points in the tree's order, with their indices in the set.
    points: Vec<[f32; 3]>,
    index: Vec<u32>,
}

/// Squared distance between two points: (x² + y²) + z², the order of a
/// plain sum over the axes.
#[inline]
pub(crate) fn dist_sq(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    x * x + y * y + z * z
}

/// Squared distance from `q` to the box `lo`–`hi` (0 inside).
#[inline]
fn box_dist_sq(q: &[f32; 3], lo: &[f32; 3], hi: &[f32; 3]) -> f32 {
    let mut d = 0.0;
    for a in 0..3 {
        let e = (lo[a] - q[a]).max(q[a] - hi[a]).max(0.0);
        d += e * e;
    }
    d
}

/// A distance with its point's index, ordered by distance and then index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ranked(f32, u32);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl AcceptTree {
    /// The tree over `points` (finite, at most u32::MAX of them).
    pub(crate) fn new(points: &[[f32; 3]]) -> AcceptTree {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * points.len() / LEAF + 1);
        nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], first: 0, count: 0 });
        // (node, start, end) still to lay out.
        let mut todo = vec![(0usize, 0usize, points.len())];
        while let Some((at, start, end)) = todo.pop() {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for &i in &order[start..end] {
                for a in 0..3 {
                    lo[a] = lo[a].min(points[i as usize][a]);
                    hi[a] = hi[a].max(points[i as usize][a]);
                }
            }
            if end - start <= LEAF {
                nodes[at] = Node { lo, hi, first: start as u32, count: (end - start) as u32 };
                continue;
            }
            let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
            let mid = start + (end - start) / 2;
            order[start..end].select_nth_unstable_by(mid - start, |&i, &j| {
                points[i as usize][axis].total_cmp(&points[j as usize][axis]).then(i.cmp(&j))
            });
            let left = nodes.len();
            nodes.push(Node { lo, hi, first: 0, count: 0 });
            nodes.push(Node { lo, hi, first: 0, count: 0 });
            nodes[at] = Node { lo, hi, first: left as u32, count: 0 };
            todo.push((left, start, mid));
            todo.push((left + 1, mid, end));
        }
        let tree_points = order.iter().map(|&i| points[i as usize]).collect();
        AcceptTree { nodes, points: tree_points, index: order }
    }

    /// Up to `m` points that `accept` takes, other than `skip`, nearest
    /// first (ties to the lower index), among the `k` nearest points of
    /// the set (`skip` counted among them): (index, squared distance).
    pub(crate) fn nearest_accepted(
        &self,
        q: &[f32; 3],
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
        k: usize,
    ) -> Vec<(usize, f32)> {
        if m == 0 || k == 0 || self.points.is_empty() {
            return Vec::new();
        }
        let mut best: Vec<Ranked> = Vec::with_capacity(m);
        if !self.search(q, skip, &accept, m, k, &mut best, None) {
            // The walk reached k points: again, keeping the k smallest
            // distances, and only the accepted points among them.
            best.clear();
            let mut kth = BinaryHeap::with_capacity(k.min(self.points.len()));
            self.search(q, skip, &accept, m, k, &mut best, Some(&mut kth));
            if let (true, Some(&t)) = (kth.len() == k, kth.peek()) {
                best.retain(|r| r.0.to_bits() <= t);
            }
        }
        best.into_iter().map(|r| (r.1 as usize, r.0)).collect()
    }

    /// The nearest other point of every point of the set, by index in the
    /// set (ties to the lower index): asked in the tree's order, so that
    /// consecutive walks meet the same nodes in the cache (in the set's own
    /// order, which may be random, the walks wait on memory: 3× slower on
    /// 32K points).
    pub(crate) fn members_nearest(&self) -> Vec<Option<(usize, f32)>> {
        let n = self.points.len();
        let found: Vec<Option<(usize, f32)>> = self
            .points
            .par_iter()
            .zip(&self.index)
            .map(|(q, &i)| self.nearest_accepted(q, Some(i as usize), |_| true, 1, n + 1).pop())
            .collect();
        let mut out = vec![None; n];
        for (&i, f) in self.index.iter().zip(found) {
            out[i as usize] = f;
        }
        out
    }

    /// The walk, depth first, nearer child first. Without `kth` it gives up
    /// (returns false) on reaching the k-th point, which few queries do;
    /// with it, `kth` keeps the bits of the k smallest distances seen
    /// (distances are never negative, so their bits order like them), and
    /// a node beyond the k-th of them is skipped: all its points rank k or
    /// later. A node beyond the m-th best accepted point is skipped too.
    /// In both cases every point nearer than an accepted one in `best` has
    /// been seen.
    #[allow(clippy::too_many_arguments)] // the query's parts, each read in the loop
    fn search(
        &self,
        q: &[f32; 3],
        skip: Option<usize>,
        accept: &impl Fn(usize) -> bool,
        m: usize,
        k: usize,
        best: &mut Vec<Ranked>,
        mut kth: Option<&mut BinaryHeap<u32>>,
    ) -> bool {
        let mut seen = 0usize;
        // Median splits keep the depth under 32 for any u32 count, and a
        // walk holds at most one entry a level plus one.
        let mut stack = [(0u32, 0.0f32); 64];
        let root = &self.nodes[0];
        stack[0] = (0, box_dist_sq(q, &root.lo, &root.hi));
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (at, b) = stack[top];
            if best.len() == m && best[m - 1].0 < b {
                continue;
            }
            if let Some(h) = kth.as_deref()
                && h.len() == k
                && h.peek().is_some_and(|&t| f32::from_bits(t) < b)
            {
                continue;
            }
            let node = self.nodes[at as usize];
            if node.count == 0 {
                let (l, r) = (&self.nodes[node.first as usize], &self.nodes[node.first as usize + 1]);
                let (dl, dr) = (box_dist_sq(q, &l.lo, &l.hi), box_dist_sq(q, &r.lo, &r.hi));
                let (near, far) =
                    if dl <= dr { ((node.first, dl), (node.first + 1, dr)) } else { ((node.first + 1, dr), (node.first, dl)) };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
                continue;
            }
            let (s, e) = (node.first as usize, (node.first + node.count) as usize);
            for (p, &j) in self.points[s..e].iter().zip(&self.index[s..e]) {
                let d = dist_sq(p, q);
                match kth.as_deref_mut() {
                    None => {
                        seen += 1;
                        if seen == k {
                            return false;
                        }
                    }
                    Some(h) if h.len() < k => h.push(d.to_bits()),
                    Some(h) => {
                        if let Some(mut t) = h.peek_mut()
                            && d.to_bits() < *t
                        {
                            *t = d.to_bits();
                        }
                    }
                }
                let j = j as usize;
                if Some(j) == skip {
                    continue;
                }
                let r = Ranked(d, j as u32);
                if (best.len() < m || r < best[m - 1]) && accept(j) {
                    let at = best.partition_point(|x| *x < r);
                    if best.len() == m {
                        best.pop();
                    }
                    best.insert(at, r);
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The answer by brute force: the first m accepted of the k nearest.
    fn brute(
        points: &[[f32; 3]],
        q: &[f32; 3],
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
        k: usize,
    ) -> Vec<(usize, f32)> {
        let mut all: Vec<Ranked> = points.iter().enumerate().map(|(j, p)| Ranked(dist_sq(p, q), j as u32)).collect();
        all.sort();
        // A point tied with the k-th distance counts as among the k nearest.
        let t = all.get(k.saturating_sub(1)).map_or(f32::INFINITY, |r| r.0);
        all.into_iter()
            .filter(|r| r.0 <= t)
            .filter(|r| Some(r.1 as usize) != skip && accept(r.1 as usize))
            .take(m)
            .map(|r| (r.1 as usize, r.0))
            .collect()
    }

    /// A small deterministic generator (xorshift), so the test needs no
    /// other crate.
    fn points(n: usize, seed: u64) -> Vec<[f32; 3]> {
        let mut s = seed | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                // Points on three planes and some in the air, with duplicates.
                let (u, v, w) = (next(), next(), next());
                match (w * 4.0) as u32 {
                    0 => [u, 0.0, v],
                    1 => [0.0, u, v],
                    2 => [u, v, 0.0],
                    _ => [(u * 8.0).floor() / 8.0, (v * 8.0).floor() / 8.0, 0.5],
                }
            })
            .collect()
    }

    #[test]
    fn answers_as_the_brute_force_does() {
        for (n, seed) in [(1, 1), (7, 2), (9, 3), (300, 4), (2048, 5)] {
            let pts = points(n, seed);
            let tree = AcceptTree::new(&pts);
            let queries = points(200, seed + 100);
            for (t, q) in queries.iter().enumerate() {
                // Predicates from none to all of the points, some rare.
                let modulus = [1usize, 2, 7, 61, 997, usize::MAX][t % 6];
                let accept = |j: usize| j % modulus.max(1) == 0 || modulus == usize::MAX && j == n - 1;
                for (m, k) in [(1, 512), (4, 512), (3, 5), (1, 1), (8, n)] {
                    let k = k.min(n);
                    let skip = (t % 3 == 0).then_some(t % n);
                    assert_eq!(
                        tree.nearest_accepted(q, skip, accept, m, k),
                        brute(&pts, q, skip, accept, m, k),
                        "n {n} query {t} m {m} k {k} modulus {modulus}"
                    );
                }
            }
        }
    }

    /// Each point's nearest other point, asked in the tree's order and
    /// handed back in the set's, is the brute force's (duplicates included:
    /// a duplicate is at distance 0, the lower index first).
    #[test]
    fn every_member_finds_its_nearest_other_point() {
        for (n, seed) in [(2, 7), (9, 8), (1000, 9)] {
            let pts = points(n, seed);
            let found = AcceptTree::new(&pts).members_nearest();
            for (i, f) in found.iter().enumerate() {
                assert_eq!(*f, brute(&pts, &pts[i], Some(i), |_| true, 1, n).pop(), "n {n} point {i}");
            }
        }
    }

    #[test]
    fn empty_trees_and_zero_counts_find_nothing() {
        let tree = AcceptTree::new(&[]);
        assert!(tree.nearest_accepted(&[0.0; 3], None, |_| true, 1, 1).is_empty());
        let tree = AcceptTree::new(&[[1.0, 2.0, 3.0]]);
        assert!(tree.nearest_accepted(&[0.0; 3], None, |_| true, 0, 1).is_empty());
        assert_eq!(tree.nearest_accepted(&[0.0; 3], None, |_| true, 1, 1), vec![(0, 14.0)]);
        assert!(tree.nearest_accepted(&[0.0; 3], Some(0), |_| true, 1, 1).is_empty());
    }
}
