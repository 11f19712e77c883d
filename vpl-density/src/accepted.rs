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

/// Points per leaf. With a leaf's distances computed side by side
/// ([`Leaves::dist_sq`]), 16 walk fewer nodes than 8 for the same points
/// (`benches/neighbours.rs`).
pub(crate) const LEAF: usize = 16;

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
    /// The leaves' points, a block of [`LEAF`] a leaf (a leaf's `first` is
    /// its block's start), by coordinate: the distances to a leaf's points
    /// are then computed side by side. Blocks are padded with points at
    /// infinity and the index `u32::MAX`, which no walk reads.
    leaves: Leaves,
    /// The points of the set.
    len: usize,
    /// Each node's parent ([`NO_PARENT`] for the root).
    parent: Vec<u32>,
}

/// [`AcceptTree::parent`] of the root.
const NO_PARENT: u32 = u32::MAX;

/// Points by coordinate, with their indices in the set.
#[derive(Clone, Debug, Default)]
struct Leaves {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    index: Vec<u32>,
}

impl Leaves {
    /// Squared distances from `q` to the [`LEAF`] points of the block at
    /// `first`, padding included (infinite), each summed (x² + y²) + z², the order of
    /// a plain sum over the axes.
    #[inline]
    fn dist_sq(&self, first: usize, q: &[f32; 3]) -> [f32; LEAF] {
        let block = |v: &[f32]| -> [f32; LEAF] { v[first..first + LEAF].try_into().unwrap_or([f32::INFINITY; LEAF]) };
        let (xs, ys, zs) = (block(&self.x), block(&self.y), block(&self.z));
        let mut d = [0.0f32; LEAF];
        for i in 0..LEAF {
            let (x, y, z) = (xs[i] - q[0], ys[i] - q[1], zs[i] - q[2]);
            d[i] = x * x + y * y + z * z;
        }
        d
    }

    /// Point `i` of the blocks.
    #[inline]
    fn point(&self, i: usize) -> [f32; 3] {
        [self.x[i], self.y[i], self.z[i]]
    }
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

/// Nodes of the tree over `n` points: a leaf holds at most [`LEAF`], a
/// larger node splits at n / 2 (at least one node).
fn node_count(n: usize) -> usize {
    if n <= LEAF { 1 } else { 1 + node_count(n / 2) + node_count(n - n / 2) }
}

/// Points whose box chooses a node's split axis, at most about: a larger
/// node takes every s-th of its points, s = ⌊n / 256⌋. The boxes of the
/// tree are tight all the same ([`build`]).
const AXIS_SAMPLES: usize = 256;

/// Subtrees at least this large build their halves in parallel.
const PARALLEL_BUILD: usize = 4096;

/// Lays out the subtree over `order` (the points `start..` of the tree's
/// order, with their indices in the set) into `node` and its descendants into `below`, whose first
/// element has index `base` in the tree: the children as the pair
/// `base, base + 1`, then the left child's descendants, then the right's.
///
/// The node splits along the longest axis of the box of some of its points
/// ([`AXIS_SAMPLES`]): the box of all of them chose it before, at a pass
/// over every point of every node (a box that is not the points', the
/// parent's cut at the split, made the nearest-hit walk 13–23 % slower: on a wall it
/// may split across the wall). Each node's own box is tight, made from
/// below: a leaf's over its points, an inner node's as the union of its
/// children's.
fn build(order: &mut [([f32; 3], u32)], start: usize, node: &mut Node, below: &mut [Node], base: usize) {
    let n = order.len();
    if n <= LEAF {
        let (lo, hi) = bounds(order.iter());
        *node = Node { lo, hi, first: start as u32, count: n as u32 };
        return;
    }
    let (lo, hi) = bounds(order.iter().step_by((n / AXIS_SAMPLES).max(1)));
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
    let mid = n / 2;
    order.select_nth_unstable_by(mid, |(p, i), (q, j)| p[axis].total_cmp(&q[axis]).then(i.cmp(j)));
    let (pair, rest) = below.split_at_mut(2);
    let (left_below, right_below) = rest.split_at_mut(node_count(mid) - 1);
    let (left, right) = pair.split_at_mut(1);
    let (order_left, order_right) = order.split_at_mut(mid);
    let (left_base, right_base) = (base + 2, base + 2 + left_below.len());
    let mut build_left = || build(order_left, start, &mut left[0], left_below, left_base);
    let mut build_right = || build(order_right, start + mid, &mut right[0], right_below, right_base);
    if n >= PARALLEL_BUILD {
        rayon::join(build_left, build_right);
    } else {
        build_left();
        build_right();
    }
    let (l, r) = (&pair[0], &pair[1]);
    let lo = [0, 1, 2].map(|a| l.lo[a].min(r.lo[a]));
    let hi = [0, 1, 2].map(|a| l.hi[a].max(r.hi[a]));
    *node = Node { lo, hi, first: base as u32, count: 0 };
}

/// The box of `points`.
fn bounds<'a>(points: impl Iterator<Item = &'a ([f32; 3], u32)>) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (p, _) in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

/// Squared distance between the boxes of two nodes (0 where they overlap):
/// no point of one lies nearer than this to a point of the other.
#[inline]
fn box_box_dist_sq(a: &Node, b: &Node) -> f32 {
    let mut d = 0.0;
    for x in 0..3 {
        let e = (a.lo[x] - b.hi[x]).max(b.lo[x] - a.hi[x]).max(0.0);
        d += e * e;
    }
    d
}

/// How far a walk of [`AcceptTree::search`] reaches.
enum Reach<'a> {
    /// It gives up (returns false) on seeing its k-th point, which few
    /// queries do.
    Count(usize),
    /// The heap keeps the bits of the k smallest distances seen (distances
    /// are never negative, so their bits order like them), and a node
    /// beyond the k-th of them is skipped: all its points rank k or later.
    Kth(usize, &'a mut BinaryHeap<u32>),
    /// Only the points within this squared distance (ties included).
    Within(f32),
}

/// A distance with its point's index, ordered by distance and then index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ranked(f32, u32);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    #[inline]
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    #[inline]
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// A query (by index) and the nearest accepted point found for it.
type Answer = (u32, Option<(usize, f32)>);

/// The nodes a walk has still to visit, with their boxes' squared
/// distances, last in first out. Median splits keep the depth under 32 for
/// any u32 count, and a walk holds at most one entry a level plus one.
/// (Two arrays of zeros, which the compiler clears at once: an array of
/// pairs was cleared entry by entry, a sixth of a search's time.)
struct Walk {
    at: [u32; 64],
    d: [f32; 64],
    top: usize,
}

impl Walk {
    #[inline]
    fn new(at: u32, d: f32) -> Walk {
        let mut w = Walk { at: [0; 64], d: [0.0; 64], top: 0 };
        w.push(at, d);
        w
    }

    #[inline]
    fn push(&mut self, at: u32, d: f32) {
        self.at[self.top] = at;
        self.d[self.top] = d;
        self.top += 1;
    }

    #[inline]
    fn pop(&mut self) -> Option<(u32, f32)> {
        self.top = self.top.checked_sub(1)?;
        Some((self.at[self.top], self.d[self.top]))
    }
}

/// The points of one leaf as lanes, by coordinate (the padding at
/// infinity, index `u32::MAX`), for the walks that answer for all of them
/// at once.
struct Lanes {
    x: [f32; LEAF],
    y: [f32; LEAF],
    z: [f32; LEAF],
    own: [u32; LEAF],
    /// The leaf's points; the lanes past them are padding.
    count: usize,
}

impl Lanes {
    /// The points of `leaf`, a leaf of `tree`.
    fn of(tree: &AcceptTree, leaf: &Node) -> Lanes {
        let s = leaf.first as usize;
        let lanes = |v: &[f32]| -> [f32; LEAF] { v[s..s + LEAF].try_into().unwrap_or([f32::INFINITY; LEAF]) };
        let own = tree.leaves.index[s..s + LEAF].try_into().unwrap_or([u32::MAX; LEAF]);
        Lanes { x: lanes(&tree.leaves.x), y: lanes(&tree.leaves.y), z: lanes(&tree.leaves.z), own, count: leaf.count as usize }
    }

    /// Squared distances from point `p` of `leaves` to the lanes, in the
    /// order of [`Leaves::dist_sq`]: (x² + y²) + z².
    // The lanes index several arrays at once, which is what lets the loop vectorise.
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn dist_sq(&self, p: usize, leaves: &Leaves) -> [f32; LEAF] {
        let (px, py, pz) = (leaves.x[p], leaves.y[p], leaves.z[p]);
        let mut d = [0.0f32; LEAF];
        for t in 0..LEAF {
            let (x, y, z) = (px - self.x[t], py - self.y[t], pz - self.z[t]);
            d[t] = x * x + y * y + z * z;
        }
        d
    }

    /// Squared distances from the lanes to `node`'s box (0 inside).
    #[inline]
    fn box_dist_sq(&self, node: &Node) -> [f32; LEAF] {
        let mut d = [0.0f32; LEAF];
        for (a, q) in [&self.x, &self.y, &self.z].into_iter().enumerate() {
            for t in 0..LEAF {
                let e = (node.lo[a] - q[t]).max(q[t] - node.hi[a]).max(0.0);
                d[t] += e * e;
            }
        }
        d
    }
}

impl AcceptTree {
    /// The tree over `points` (finite, at most u32::MAX of them). The
    /// halves of a large node are built in parallel; each subtree's nodes
    /// have their place fixed by its size alone ([`node_count`]), so the
    /// tree is the same on any number of threads.
    pub(crate) fn new(points: &[[f32; 3]]) -> AcceptTree {
        // The points move with their indices, so that the splits compare
        // coordinates at hand rather than through the indices.
        let mut items: Vec<([f32; 3], u32)> = points.iter().enumerate().map(|(i, &p)| (p, i as u32)).collect();
        let empty = Node { lo: [0.0; 3], hi: [0.0; 3], first: 0, count: 0 };
        let mut nodes = vec![empty; node_count(points.len())];
        if !points.is_empty() {
            let (root, below) = nodes.split_at_mut(1);
            build(&mut items, 0, &mut root[0], below, 1);
        }
        // Each leaf's points into a block of its own, in the order of the
        // nodes (which depends on the sizes alone).
        let blocks = nodes.iter().filter(|n| n.count > 0).count();
        let mut leaves = Leaves {
            x: vec![f32::INFINITY; blocks * LEAF],
            y: vec![f32::INFINITY; blocks * LEAF],
            z: vec![f32::INFINITY; blocks * LEAF],
            index: vec![u32::MAX; blocks * LEAF],
        };
        for (block, node) in nodes.iter_mut().filter(|n| n.count > 0).enumerate() {
            let (s, b) = (node.first as usize, block * LEAF);
            for (t, (p, i)) in items[s..s + node.count as usize].iter().enumerate() {
                (leaves.x[b + t], leaves.y[b + t], leaves.z[b + t], leaves.index[b + t]) = (p[0], p[1], p[2], *i);
            }
            node.first = b as u32;
        }
        let mut parent = vec![NO_PARENT; nodes.len()];
        if !points.is_empty() {
            for (i, n) in nodes.iter().enumerate().filter(|(_, n)| n.count == 0) {
                parent[n.first as usize] = i as u32;
                parent[n.first as usize + 1] = i as u32;
            }
        }
        AcceptTree { nodes, leaves, len: points.len(), parent }
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
        self.nearest_accepted_reach(q, skip, accept, m, k).0
    }

    /// [`AcceptTree::nearest_accepted`], and the reach of the k-th nearest
    /// point ([`AcceptTree::reach_sq`]) when the walk had to find it.
    pub(crate) fn nearest_accepted_reach(
        &self,
        q: &[f32; 3],
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
        k: usize,
    ) -> (Vec<(usize, f32)>, Option<f32>) {
        if m == 0 || k == 0 || self.len == 0 {
            return (Vec::new(), None);
        }
        let mut reach = None;
        let mut best: Vec<Ranked> = Vec::with_capacity(m);
        if !self.search(q, skip, &accept, m, &mut best, Reach::Count(k)) {
            // The walk reached k points: again, keeping the k smallest
            // distances, and only the accepted points among them.
            best.clear();
            let mut kth = BinaryHeap::with_capacity(k.min(self.len));
            self.search(q, skip, &accept, m, &mut best, Reach::Kth(k, &mut kth));
            // The k-th distance's bits (none: the set has fewer points).
            let t = kth.peek().copied().filter(|_| kth.len() == k);
            if let Some(t) = t {
                best.retain(|r| r.0.to_bits() <= t);
            }
            reach = Some(t.map_or(f32::INFINITY, f32::from_bits));
        }
        (best.into_iter().map(|r| (r.1 as usize, r.0)).collect(), reach)
    }

    /// The squared distance of the `k`-th nearest point of the set to `q`
    /// (infinite when the set has fewer than `k` points): the reach of
    /// [`AcceptTree::nearest_accepted`] with this `k`, whose answer
    /// [`AcceptTree::nearest_accepted_within`] then finds in one walk.
    pub(crate) fn reach_sq(&self, q: &[f32; 3], k: usize) -> f32 {
        if k == 0 || k > self.len {
            return f32::INFINITY;
        }
        let mut kth = BinaryHeap::with_capacity(k);
        self.search(q, None, &|_| false, 1, &mut Vec::new(), Reach::Kth(k, &mut kth));
        kth.peek().map_or(f32::INFINITY, |&t| f32::from_bits(t))
    }

    /// Up to `m` points that `accept` takes, other than `skip`, nearest
    /// first (ties to the lower index), within squared distance `r2` of
    /// `q` (ties included). With `r2` from [`AcceptTree::reach_sq`] (k), it
    /// is [`AcceptTree::nearest_accepted`]'s answer (m, k): every point of
    /// the k nearest lies within it, and every point within it but the
    /// ties of the k-th is among them.
    pub(crate) fn nearest_accepted_within(
        &self,
        q: &[f32; 3],
        skip: Option<usize>,
        accept: impl Fn(usize) -> bool,
        m: usize,
        r2: f32,
    ) -> Vec<(usize, f32)> {
        if m == 0 || self.len == 0 || r2.is_nan() {
            return Vec::new();
        }
        let mut best: Vec<Ranked> = Vec::with_capacity(m);
        self.search(q, skip, &accept, m, &mut best, Reach::Within(r2));
        best.into_iter().map(|r| (r.1 as usize, r.0)).collect()
    }

    /// For each of `queries`, the nearest point of the set that
    /// `accept(query, point)` takes, among the `k` nearest points of the
    /// set: what [`AcceptTree::nearest_accepted`] answers with m = 1 and no
    /// point skipped, for all of them at once.
    ///
    /// The queries are put in a tree of their own, and each of its leaves
    /// walks this tree once, as [`AcceptTree::leaf_nearest`] does: a node is
    /// skipped when its box lies beyond every query's best so far, and a
    /// query skips a node beyond its own best. Every point nearer than a
    /// query's answer lies in a node the query visited, so a query that has
    /// visited fewer than `k` points has its answer among its `k` nearest:
    /// the answer is exact. A query that reaches `k` visited points (or
    /// finds nothing, which visits them all) leaves the walk and is asked
    /// alone.
    pub(crate) fn nearest_accepted_each(
        &self,
        queries: &[[f32; 3]],
        accept: &(impl Fn(usize, usize) -> bool + Sync),
        k: usize,
    ) -> Vec<Option<(usize, f32)>> {
        if k == 0 || self.len == 0 || queries.is_empty() {
            return vec![None; queries.len()];
        }
        self.nearest_accepted_each_of(&AcceptTree::new(queries), accept, k)
    }

    /// [`AcceptTree::nearest_accepted_each`] for the points of `queries`, a
    /// tree over them, in their order.
    pub(crate) fn nearest_accepted_each_of(
        &self,
        queries: &AcceptTree,
        accept: &(impl Fn(usize, usize) -> bool + Sync),
        k: usize,
    ) -> Vec<Option<(usize, f32)>> {
        let mut out = vec![None; queries.len];
        if k == 0 || self.len == 0 || queries.len == 0 {
            return out;
        }
        let leaves: Vec<usize> = (0..queries.nodes.len()).filter(|&i| queries.nodes[i].count > 0).collect();
        let found: Vec<Vec<Answer>> = leaves.par_iter().map(|&l| self.leaf_accepted(queries, l, accept, k)).collect();
        for (i, answer) in found.into_iter().flatten() {
            out[i as usize] = answer;
        }
        out
    }

    /// [`AcceptTree::nearest_accepted_each`] for the queries of leaf `l` of
    /// `tree`: (query, answer) for each of them.
    fn leaf_accepted(&self, tree: &AcceptTree, l: usize, accept: &impl Fn(usize, usize) -> bool, k: usize) -> Vec<Answer> {
        let leaf = tree.nodes[l];
        let (s, e) = (leaf.first as usize, (leaf.first + leaf.count) as usize);
        let qs: Vec<[f32; 3]> = (s..e).map(|i| tree.leaves.point(i)).collect();
        let own = &tree.leaves.index[s..e];
        let mut best = [Ranked(f32::INFINITY, u32::MAX); LEAF];
        let mut seen = [0usize; LEAF];
        // A query that left the walk (seen k points) bounds nothing.
        let bound = |best: &[Ranked; LEAF], seen: &[usize; LEAF]| {
            best[..qs.len()].iter().zip(seen).filter(|(_, n)| **n < k).fold(f32::NEG_INFINITY, |m, (r, _)| m.max(r.0))
        };
        let mut walk = Walk::new(0, box_box_dist_sq(&leaf, &self.nodes[0]));
        while let Some((at, b)) = walk.pop() {
            if b > bound(&best, &seen) {
                continue;
            }
            let node = self.nodes[at as usize];
            if node.count == 0 {
                self.push_children(&mut walk, &leaf, &node);
                continue;
            }
            let ns = node.first as usize;
            let theirs = &self.leaves.index[ns..ns + node.count as usize];
            for (((q, &i), b), n) in qs.iter().zip(own).zip(best.iter_mut()).zip(seen.iter_mut()) {
                if *n >= k || box_dist_sq(q, &node.lo, &node.hi) > b.0 {
                    continue;
                }
                *n += theirs.len();
                let d = self.leaves.dist_sq(ns, q);
                for (&d, &j) in d.iter().zip(theirs) {
                    if (d < b.0 || (d == b.0 && j < b.1)) && accept(i as usize, j as usize) {
                        *b = Ranked(d, j);
                    }
                }
            }
        }
        qs.iter()
            .zip(own)
            .zip(best.iter().zip(&seen))
            .map(|((q, &i), (b, &n))| {
                let answer = if n < k {
                    (b.1 != u32::MAX).then_some((b.1 as usize, b.0))
                } else {
                    self.nearest_accepted(q, None, |j| accept(i as usize, j), 1, k).pop()
                };
                (i, answer)
            })
            .collect()
    }

    /// Pushes the children of `node` onto a walk for the points of `leaf`,
    /// the nearer by box-to-box distance last, so that it is visited first.
    #[inline]
    fn push_children(&self, walk: &mut Walk, leaf: &Node, node: &Node) {
        let (cl, cr) = (node.first, node.first + 1);
        let dl = box_box_dist_sq(leaf, &self.nodes[cl as usize]);
        let dr = box_box_dist_sq(leaf, &self.nodes[cr as usize]);
        let (near, far) = if dl <= dr { ((cl, dl), (cr, dr)) } else { ((cr, dr), (cl, dl)) };
        walk.push(far.0, far.1);
        walk.push(near.0, near.1);
    }

    /// The nearest other point of every point of the set, by index in the
    /// set (ties to the lower index). One walk per leaf answers for all its
    /// points at once ([`AcceptTree::leaf_nearest`]): a walk per point
    /// descends the same path for each of the leaf's points, and on 32K points that was 3×
    /// slower (in the set's own order, which may be random, a walk per
    /// point also waits on memory: 3× slower again).
    pub(crate) fn members_nearest(&self) -> Vec<Option<(usize, f32)>> {
        self.per_member(None, |l| self.leaf_nearest(l).map(|r| (r.1 != u32::MAX).then_some((r.1 as usize, r.0))))
    }

    /// The squared distance from every point of the set to its `k`-th
    /// nearest other point, by index in the set (infinite where the set
    /// has fewer than k other points; `k` at least 1). One walk per leaf
    /// answers for its points at once, as [`AcceptTree::members_nearest`]
    /// does, each point keeping its k smallest distances.
    pub(crate) fn members_kth(&self, k: usize) -> Vec<f32> {
        if k == 0 {
            return vec![f32::INFINITY; self.len];
        }
        self.per_member(f32::INFINITY, |l| self.leaf_kth(l, k))
    }

    /// The answers of `leaf` (one per point of a leaf, in the leaf's order;
    /// the leaves in parallel) by index in the set, `none` where no leaf
    /// answers.
    fn per_member<T: Copy + Send>(&self, none: T, leaf: impl Fn(usize) -> [T; LEAF] + Sync) -> Vec<T> {
        let leaves: Vec<usize> = (0..self.nodes.len()).filter(|&i| self.nodes[i].count > 0).collect();
        let found: Vec<[T; LEAF]> = leaves.par_iter().map(|&l| leaf(l)).collect();
        let mut out = vec![none; self.len];
        for (&l, answers) in leaves.iter().zip(found) {
            let node = self.nodes[l];
            let s = node.first as usize;
            for (&i, a) in self.leaves.index[s..s + node.count as usize].iter().zip(answers) {
                out[i as usize] = a;
            }
        }
        out
    }

    /// One walk for all the points of leaf `l` (its lanes `q`): the leaf's
    /// own points first, so that the walk starts with bounds, then, from
    /// the leaf's parent up to the root, the subtree of each ancestor on the
    /// other side (the nearest ancestor's first), each walked nearer child
    /// first. The nodes on the leaf's own path hold it, so they are never
    /// tested. A node is skipped when its box lies beyond
    /// every lane's bound (`bounds` of `state`; with `ties`, a node at
    /// exactly a lane's bound is still walked). `visit` takes each leaf
    /// node walked. The padding lanes must hold a negative bound, which no
    /// box is within.
    fn walk_for_leaf<S>(
        &self,
        (l, q): (usize, &Lanes),
        state: &mut S,
        bounds: impl Fn(&S) -> &[f32; LEAF],
        ties: bool,
        mut visit: impl FnMut(&mut S, &Node),
    ) {
        let leaf = self.nodes[l];
        visit(state, &leaf);
        let within = |d: f32, bound: f32| if ties { d <= bound } else { d < bound };
        let mut child = l as u32;
        while let Some(&up) = self.parent.get(child as usize).filter(|&&p| p != NO_PARENT) {
            let first = self.nodes[up as usize].first;
            let other = if first == child { first + 1 } else { first };
            let mut walk = Walk::new(other, box_box_dist_sq(&leaf, &self.nodes[other as usize]));
            while let Some((at, b)) = walk.pop() {
                let lane_bounds = bounds(state);
                if !within(b, lane_bounds[..q.count].iter().fold(0.0f32, |m, &d| m.max(d))) {
                    continue;
                }
                let node = self.nodes[at as usize];
                let d = q.box_dist_sq(&node);
                let mut any = false;
                for t in 0..LEAF {
                    any |= within(d[t], lane_bounds[t]);
                }
                if !any {
                    continue;
                }
                if node.count == 0 {
                    self.push_children(&mut walk, &leaf, &node);
                } else {
                    visit(state, &node);
                }
            }
            child = up;
        }
    }

    /// The k-th smallest distance from each point of leaf `l` to the other
    /// points, in the leaf's order: each lane keeps its k smallest so far,
    /// sorted, and a point of a visited node enters a lane's list only
    /// where it is nearer than the lane's k-th (tested for all lanes at
    /// once). A node is skipped when its box lies beyond every lane's k-th:
    /// it can hold no smaller distance. The multiset of the k smallest, so
    /// its k-th, does not depend on the order the points are met in.
    fn leaf_kth(&self, l: usize, k: usize) -> [f32; LEAF] {
        let q = Lanes::of(self, &self.nodes[l]);
        // Lane t's k smallest, ascending, at t·k; its k-th apart. The
        // padding lanes hold a negative k-th, which nothing beats.
        let mut lists = vec![f32::INFINITY; LEAF * k];
        let mut kth = [f32::INFINITY; LEAF];
        kth[q.count..].fill(-1.0);
        self.walk_for_leaf(
            (l, &q),
            &mut kth,
            |kth| kth,
            false,
            |kth, node| {
                let ns = node.first as usize;
                for p in ns..ns + node.count as usize {
                    let j = self.leaves.index[p];
                    let d = q.dist_sq(p, &self.leaves);
                    let mut nearer = [false; LEAF];
                    for t in 0..LEAF {
                        nearer[t] = (d[t] < kth[t]) & (q.own[t] != j);
                    }
                    if !nearer.contains(&true) {
                        continue;
                    }
                    for t in 0..q.count {
                        if nearer[t] {
                            let list = &mut lists[t * k..(t + 1) * k];
                            let at = list.partition_point(|&e| e <= d[t]);
                            list.copy_within(at..k - 1, at + 1);
                            list[at] = d[t];
                            kth[t] = list[k - 1];
                        }
                    }
                }
            },
        );
        kth
    }

    /// The nearest other point of each point of leaf `l`, in the leaf's
    /// order (ties to the lower index), by one walk for all of them
    /// ([`AcceptTree::walk_for_leaf`]) that skips a node whose box lies
    /// farther from every point of the leaf than its best so far. A node at
    /// exactly that distance is still walked: it may hold a tie of lower
    /// index.
    ///
    /// The leaf's points are lanes: each point of a visited node is compared
    /// with all of them at once (distances, then the better of the two by
    /// distance and index, as selects). The best of each lane is the least
    /// (distance, index) over the points it was compared with, whatever
    /// their order.
    fn leaf_nearest(&self, l: usize) -> [Ranked; LEAF] {
        let q = Lanes::of(self, &self.nodes[l]);
        // The padding lanes hold a negative best, which no distance beats
        // and no box is within.
        let mut best = ([f32::INFINITY; LEAF], [u32::MAX; LEAF]);
        best.0[q.count..].fill(-1.0);
        self.walk_for_leaf(
            (l, &q),
            &mut best,
            |best| &best.0,
            true,
            |(bd, bi), node| {
                let ns = node.first as usize;
                for k in ns..ns + node.count as usize {
                    let j = self.leaves.index[k];
                    let d = q.dist_sq(k, &self.leaves);
                    for t in 0..LEAF {
                        let better = ((d[t] < bd[t]) | ((d[t] == bd[t]) & (j < bi[t]))) & (q.own[t] != j);
                        // Selects as masks, which SSE2 has (it has no blend).
                        let m = 0u32.wrapping_sub(better as u32);
                        bd[t] = f32::from_bits((d[t].to_bits() & m) | (bd[t].to_bits() & !m));
                        bi[t] = (j & m) | (bi[t] & !m);
                    }
                }
            },
        );
        let mut ranked = [Ranked(f32::INFINITY, u32::MAX); LEAF];
        for (r, (&d, &i)) in ranked.iter_mut().zip(best.0.iter().zip(&best.1)).take(q.count) {
            *r = Ranked(d, i);
        }
        ranked
    }

    /// Every point within squared distance `r2` of `q` (`r2` not NaN), as
    /// (index in the set, squared distance), in the tree's order.
    pub(crate) fn within(&self, q: &[f32; 3], r2: f32) -> Vec<(usize, f32)> {
        let mut out = Vec::new();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if box_dist_sq(q, &node.lo, &node.hi) > r2 {
                continue;
            }
            if node.count == 0 {
                stack[top] = node.first + 1;
                stack[top + 1] = node.first;
                top += 2;
                continue;
            }
            let s = node.first as usize;
            let d = self.leaves.dist_sq(s, q);
            for (&d, &j) in d.iter().zip(&self.leaves.index[s..s + node.count as usize]) {
                if d <= r2 {
                    out.push((j as usize, d));
                }
            }
        }
        out
    }

    /// The walk, depth first, nearer child first, for the `m` nearest
    /// accepted points, as far as `reach` says ([`Reach`]). A node beyond
    /// the m-th best accepted point is skipped too. Every point nearer than
    /// an accepted one in `best` (and within the reach) has been seen.
    /// Returns false when a [`Reach::Count`] walk gave up.
    fn search(
        &self,
        q: &[f32; 3],
        skip: Option<usize>,
        accept: &impl Fn(usize) -> bool,
        m: usize,
        best: &mut Vec<Ranked>,
        reach: Reach,
    ) -> bool {
        // `k`: the points a counting walk may see (none: it does not count).
        let (k, mut kth, r2) = match reach {
            Reach::Count(k) => (Some(k), None, f32::INFINITY),
            Reach::Kth(k, heap) => (Some(k), Some(heap), f32::INFINITY),
            Reach::Within(r2) => (None, None, r2),
        };
        let mut seen = 0usize;
        let root = &self.nodes[0];
        let mut walk = Walk::new(0, box_dist_sq(q, &root.lo, &root.hi));
        while let Some((at, b)) = walk.pop() {
            if (best.len() == m && best[m - 1].0 < b) || b > r2 {
                continue;
            }
            if let Some(h) = kth.as_deref()
                && Some(h.len()) == k
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
                walk.push(far.0, far.1);
                walk.push(near.0, near.1);
                continue;
            }
            let s = node.first as usize;
            let d = self.leaves.dist_sq(s, q);
            for (&d, &j) in d.iter().zip(&self.leaves.index[s..s + node.count as usize]) {
                match (kth.as_deref_mut(), k) {
                    (None, Some(k)) => {
                        seen += 1;
                        if seen == k {
                            return false;
                        }
                    }
                    (None, None) if d > r2 => continue,
                    (None, None) => {}
                    (Some(h), Some(k)) if h.len() < k => h.push(d.to_bits()),
                    (Some(h), _) => {
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

    /// Squared distance between two points: (x² + y²) + z², the order of a
    /// plain sum over the axes.
    #[inline]
    fn dist_sq(a: &[f32; 3], b: &[f32; 3]) -> f32 {
        let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
        x * x + y * y + z * z
    }

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

    /// Within the reach of the k-th nearest point, one walk answers as
    /// the counting walk and its second walk do, whatever the predicate
    /// (from none of the points to all, some rare), m and k (ties at the
    /// reach included: the coarse grid holds many).
    #[test]
    fn within_the_reach_answers_as_the_k_nearest_do() {
        let grid: Vec<[f32; 3]> = points(2000, 31).into_iter().map(|p| p.map(|x| (x * 6.0).floor())).collect();
        for (n, pts) in [(1, points(1, 32)), (9, points(9, 33)), (300, points(300, 34)), (2048, points(2048, 35)), (2000, grid)] {
            let tree = AcceptTree::new(&pts);
            let queries: Vec<[f32; 3]> = points(100, 36).into_iter().chain(pts.iter().take(100).copied()).collect();
            for (t, q) in queries.iter().enumerate() {
                let modulus = [1usize, 2, 7, 61, 997, usize::MAX][t % 6];
                let accept = |j: usize| j % modulus.max(1) == 0 || modulus == usize::MAX && j == n - 1;
                for (m, k) in [(1, 512), (4, 512), (3, 5), (1, 1), (8, n)] {
                    let k = k.min(n);
                    let skip = (t % 3 == 0).then_some(t % n);
                    assert_eq!(
                        tree.nearest_accepted_within(q, skip, accept, m, tree.reach_sq(q, k)),
                        tree.nearest_accepted(q, skip, accept, m, k),
                        "n {n} query {t} m {m} k {k} modulus {modulus}"
                    );
                }
            }
        }
    }

    /// All queries at once answer as each alone does, whatever the
    /// predicate (from none of the points to all, some rare) and k.
    #[test]
    fn queries_at_once_answer_as_each_alone() {
        for (n, seed) in [(1, 21), (9, 22), (300, 23), (2048, 24)] {
            let pts = points(n, seed);
            let tree = AcceptTree::new(&pts);
            let queries = points(700, seed + 100);
            for modulus in [1usize, 2, 7, 61, 997, usize::MAX] {
                let accept = |q: usize, j: usize| (j + q % 3) % modulus.max(1) == 0;
                for k in [1, 5, 512, n] {
                    let k = k.min(n);
                    let each = tree.nearest_accepted_each(&queries, &accept, k);
                    for (t, q) in queries.iter().enumerate() {
                        assert_eq!(
                            each[t],
                            tree.nearest_accepted(q, None, |j| accept(t, j), 1, k).pop(),
                            "n {n} query {t} k {k} modulus {modulus}"
                        );
                    }
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
        // On a coarse grid: many duplicates and ties, which go to the lower index.
        let pts: Vec<[f32; 3]> = points(2000, 10).into_iter().map(|p| p.map(|x| (x * 6.0).floor())).collect();
        let found = AcceptTree::new(&pts).members_nearest();
        for (i, f) in found.iter().enumerate() {
            assert_eq!(*f, brute(&pts, &pts[i], Some(i), |_| true, 1, pts.len()).pop(), "grid point {i}");
        }
    }

    #[test]
    fn balls_hold_what_brute_force_finds() {
        let pts = points(3000, 11);
        let tree = AcceptTree::new(&pts);
        for (i, r2) in [(0, 0.0), (5, 0.001), (17, 0.01), (40, 0.2), (99, 4.0)] {
            let mut found = tree.within(&pts[i], r2);
            found.sort_by_key(|f| f.0);
            let brute: Vec<(usize, f32)> =
                pts.iter().enumerate().map(|(j, p)| (j, dist_sq(p, &pts[i]))).filter(|&(_, d)| d <= r2).collect();
            assert_eq!(found, brute, "point {i} r² {r2}");
        }
    }

    /// The tree is laid out by the sizes alone: built on one thread or on
    /// several, it is the same.
    #[test]
    fn the_tree_is_the_same_on_any_number_of_threads() {
        let pts = points(20_000, 12);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| AcceptTree::new(&pts));
        let four = rayon::ThreadPoolBuilder::new().num_threads(4).build().unwrap().install(|| AcceptTree::new(&pts));
        assert_eq!(one.leaves.index, four.leaves.index);
        assert_eq!(one.nodes.len(), four.nodes.len());
        for (a, b) in one.nodes.iter().zip(&four.nodes) {
            assert_eq!((a.lo, a.hi, a.first, a.count), (b.lo, b.hi, b.first, b.count));
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
