//! The tree: a binary radix tree over the lights in Morton order (Karras,
//! "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d
//! Trees", HPG 2012), every inner node holding the bounds of its lights.

use crate::cone::Cone;
use crate::morton;
use glam::Vec3;
use rayon::prelude::*;

/// One light as the tree sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Position.
    pub p: Vec3,
    /// Unit normal of the side that emits.
    pub n: Vec3,
    /// Power (for a VPL, the luminance of its flux): what the tree sums and
    /// a cut samples by.
    pub power: f32,
}

/// What a subtree's lights share: the box of their positions, the cone of
/// their normals and their summed power. An empty subtree has an empty box
/// (`lo` +∞, `hi` −∞), the empty cone and no power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Least corner of the positions' box.
    pub lo: Vec3,
    /// Greatest corner.
    pub hi: Vec3,
    /// The normals' cone.
    pub cone: Cone,
    /// Summed power.
    pub power: f32,
}

impl Bounds {
    /// Bounds of no light.
    pub const EMPTY: Bounds = Bounds { lo: Vec3::INFINITY, hi: Vec3::NEG_INFINITY, cone: Cone::EMPTY, power: 0.0 };

    /// The bounds of one slot: its light, or none (an empty slot, or a light
    /// whose position or power is not finite, or whose power is not
    /// positive: it sends nothing a cut could sample).
    pub fn of(slot: Option<&Emitter>) -> Bounds {
        match slot {
            Some(e) if e.p.is_finite() && e.power.is_finite() && e.power > 0.0 => {
                Bounds { lo: e.p, hi: e.p, cone: Cone::of(e.n), power: e.power }
            }
            _ => Bounds::EMPTY,
        }
    }

    /// Whether it bounds no light.
    pub fn is_empty(&self) -> bool {
        self.power <= 0.0 && self.cone.is_empty()
    }

    /// The bounds of both.
    pub fn union(&self, other: &Bounds) -> Bounds {
        Bounds { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi), cone: self.cone.union(other.cone), power: self.power + other.power }
    }
}

/// A child: an inner node of the tree, or a slot of the light set (a leaf).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Child {
    /// Inner node `i` ([`LightTree::node`]).
    Node(u32),
    /// The light in slot `s`.
    Slot(u32),
}

/// High bit of a packed child: a slot.
const SLOT: u32 = 1 << 31;

fn pack(c: Child) -> u32 {
    match c {
        Child::Node(i) => i,
        Child::Slot(s) => s | SLOT,
    }
}

fn unpack(c: u32) -> Child {
    if c & SLOT != 0 { Child::Slot(c & !SLOT) } else { Child::Node(c) }
}

/// An inner node: its subtree's bounds and its two children.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// What its lights share.
    pub bounds: Bounds,
    children: [u32; 2],
}

impl Node {
    /// Its children (left: the lower Morton codes).
    pub fn children(&self) -> [Child; 2] {
        [unpack(self.children[0]), unpack(self.children[1])]
    }
}

/// Why a light tree refused a request.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum LightTreeError {
    /// The light set has another number of slots than the tree was built for.
    #[error("the tree was built over {built} slots, not {given}")]
    Slots {
        /// Slots at build time.
        built: usize,
        /// Slots given.
        given: usize,
    },
    /// A changed slot is past the set's end.
    #[error("slot {slot} is past the set's {slots} slots")]
    Slot {
        /// The slot named.
        slot: usize,
        /// The set's slots.
        slots: usize,
    },
    /// More slots than a tree can address (2³¹ − 1).
    #[error("{0} slots are more than a light tree can address")]
    TooMany(usize),
}

/// A light tree over the slots of a light set (empty slots included, as
/// leaves of no light, so that a light put there later is refitted in).
///
/// Built in Morton order of the lights' positions (empty slots last), as a
/// binary radix tree, each inner node holding its subtree's [`Bounds`]:
/// 52 bytes an inner node and 8 bytes of parents a slot, about 60 bytes a
/// light. The build is deterministic: the same set gives the same tree, bit
/// for bit, on any number of threads.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Each inner node's parent (`u32::MAX` for the root).
    node_parent: Vec<u32>,
    /// Each slot's parent (`u32::MAX` where the slot is the root).
    slot_parent: Vec<u32>,
    root: Option<Child>,
}

impl LightTree {
    /// The tree over `slots`.
    pub fn build(slots: &[Option<Emitter>]) -> Result<LightTree, LightTreeError> {
        let n = slots.len();
        if n >= SLOT as usize {
            return Err(LightTreeError::TooMany(n));
        }
        if n == 0 {
            return Ok(LightTree { nodes: Vec::new(), node_parent: Vec::new(), slot_parent: Vec::new(), root: None });
        }
        let leaves: Vec<Bounds> = slots.par_iter().map(|s| Bounds::of(s.as_ref())).collect();
        // Morton order of the lights' positions, in their box; empty slots last.
        let (lo, hi) =
            leaves.iter().filter(|b| !b.is_empty()).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), b| (l.min(b.lo), h.max(b.hi)));
        let extent = (hi - lo).max(Vec3::ZERO);
        let mut keys: Vec<(u64, u32)> = leaves
            .par_iter()
            .enumerate()
            .map(|(s, b)| (if b.is_empty() { u64::MAX } else { morton::code(b.lo, lo, extent) }, s as u32))
            .collect();
        keys.par_sort_unstable();
        if n == 1 {
            return Ok(LightTree { nodes: Vec::new(), node_parent: Vec::new(), slot_parent: vec![u32::MAX], root: Some(Child::Slot(0)) });
        }
        // Karras's split of each inner node, all independent.
        let delta = |i: usize, j: i64| -> i32 {
            if j < 0 || j >= n as i64 {
                return -1;
            }
            let (a, b) = (keys[i].0, keys[j as usize].0);
            if a != b { (a ^ b).leading_zeros() as i32 } else { 64 + ((i as u64) ^ (j as u64)).leading_zeros() as i32 }
        };
        let children: Vec<[u32; 2]> = (0..n - 1)
            .into_par_iter()
            .map(|i| {
                let ii = i as i64;
                let d: i64 = if delta(i, ii + 1) > delta(i, ii - 1) { 1 } else { -1 };
                let d_min = delta(i, ii - d);
                let mut l_max: i64 = 2;
                while delta(i, ii + l_max * d) > d_min {
                    l_max *= 2;
                }
                let mut l: i64 = 0;
                let mut t = l_max / 2;
                while t >= 1 {
                    if delta(i, ii + (l + t) * d) > d_min {
                        l += t;
                    }
                    t /= 2;
                }
                let j = ii + l * d;
                let d_node = delta(i, j);
                let mut s: i64 = 0;
                let mut t = l;
                loop {
                    t = (t + 1) / 2;
                    if delta(i, ii + (s + t) * d) > d_node {
                        s += t;
                    }
                    if t == 1 {
                        break;
                    }
                }
                let gamma = ii + s * d + d.min(0);
                let (first, last) = (ii.min(j), ii.max(j));
                let left = if first == gamma { pack(Child::Slot(keys[gamma as usize].1)) } else { gamma as u32 };
                let right = if last == gamma + 1 { pack(Child::Slot(keys[gamma as usize + 1].1)) } else { gamma as u32 + 1 };
                [left, right]
            })
            .collect();
        let mut node_parent = vec![u32::MAX; n - 1];
        let mut slot_parent = vec![u32::MAX; n];
        for (i, c) in children.iter().enumerate() {
            for &c in c {
                match unpack(c) {
                    Child::Node(k) => node_parent[k as usize] = i as u32,
                    Child::Slot(s) => slot_parent[s as usize] = i as u32,
                }
            }
        }
        let mut tree = LightTree {
            nodes: children.into_iter().map(|children| Node { bounds: Bounds::EMPTY, children }).collect(),
            node_parent,
            slot_parent,
            root: Some(Child::Node(0)),
        };
        tree.fit_all(&leaves);
        Ok(tree)
    }

    /// Every inner node's bounds, deepest level first, each level in
    /// parallel (a node from its two children, so the order of a level's
    /// nodes does not change a bit).
    fn fit_all(&mut self, leaves: &[Bounds]) {
        let mut depth = vec![0u32; self.nodes.len()];
        let mut stack = vec![0u32];
        let mut deepest = 0;
        while let Some(i) = stack.pop() {
            for c in self.nodes[i as usize].children() {
                if let Child::Node(k) = c {
                    depth[k as usize] = depth[i as usize] + 1;
                    deepest = deepest.max(depth[k as usize]);
                    stack.push(k);
                }
            }
        }
        let mut levels = vec![Vec::new(); deepest as usize + 1];
        for (i, &d) in depth.iter().enumerate() {
            levels[d as usize].push(i as u32);
        }
        for level in levels.iter().rev() {
            let fitted: Vec<Bounds> = level.par_iter().map(|&i| self.fit(i, leaves)).collect();
            for (&i, b) in level.iter().zip(fitted) {
                self.nodes[i as usize].bounds = b;
            }
        }
    }

    /// Node `i`'s bounds from its children's.
    fn fit(&self, i: u32, leaves: &[Bounds]) -> Bounds {
        let [a, b] = self.nodes[i as usize].children();
        self.bounds_in(a, leaves).union(&self.bounds_in(b, leaves))
    }

    fn bounds_in(&self, c: Child, leaves: &[Bounds]) -> Bounds {
        match c {
            Child::Node(k) => self.nodes[k as usize].bounds,
            Child::Slot(s) => leaves[s as usize],
        }
    }

    /// Brings the tree up to date with `slots` where only the slots in
    /// `changed` differ from the set it was last built or refitted with:
    /// each changed slot's ancestors are fitted again, leaf to root. The
    /// shape stays (a light that moved far makes its nodes looser, never
    /// wrong); the bounds are those a build of this shape would give, bit for
    /// bit.
    pub fn refit(&mut self, slots: &[Option<Emitter>], changed: &[usize]) -> Result<(), LightTreeError> {
        if slots.len() != self.slot_parent.len() {
            return Err(LightTreeError::Slots { built: self.slot_parent.len(), given: slots.len() });
        }
        if let Some(&slot) = changed.iter().find(|&&s| s >= slots.len()) {
            return Err(LightTreeError::Slot { slot, slots: slots.len() });
        }
        let bounds = |c: Child, nodes: &[Node]| match c {
            Child::Node(k) => nodes[k as usize].bounds,
            Child::Slot(s) => Bounds::of(slots[s as usize].as_ref()),
        };
        // Walks in turn: a node shared by two walks is fitted last by the
        // later one, after both children are final.
        for &s in changed {
            let mut at = self.slot_parent[s];
            while at != u32::MAX {
                let [a, b] = self.nodes[at as usize].children();
                self.nodes[at as usize].bounds = bounds(a, &self.nodes).union(&bounds(b, &self.nodes));
                at = self.node_parent[at as usize];
            }
        }
        Ok(())
    }

    /// The root: an inner node, a slot (a set of one), or `None` (no slot).
    pub fn root(&self) -> Option<Child> {
        self.root
    }

    /// Inner node `i`.
    pub fn node(&self, i: u32) -> &Node {
        &self.nodes[i as usize]
    }

    /// The inner nodes.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Slots the tree was built over.
    pub fn slots(&self) -> usize {
        self.slot_parent.len()
    }

    /// The bounds of child `c` of a tree over `slots`.
    pub fn bounds(&self, c: Child, slots: &[Option<Emitter>]) -> Bounds {
        match c {
            Child::Node(k) => self.nodes[k as usize].bounds,
            Child::Slot(s) => Bounds::of(slots.get(s as usize).and_then(Option::as_ref)),
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>() + (self.node_parent.capacity() + self.slot_parent.capacity()) * 4
    }
}
