//! The tree against its definition, on random sets: every inner node bounds
//! exactly its subtree's lights; a refit of a few slots equals fitting every
//! node again; the build is the same on one thread and on two.

use glam::Vec3;
use vpl_lighttree::{Bounds, Child, Emitter, LightTree, LightTreeError};

/// A xorshift stream, seeded: the tests' random sets.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// `n` slots, about one in eight empty, some sharing a position.
fn set(n: usize, seed: u64) -> Vec<Option<Emitter>> {
    let mut r = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut out: Vec<Option<Emitter>> = Vec::with_capacity(n);
    for i in 0..n {
        if r.next() < 0.125 {
            out.push(None);
            continue;
        }
        let p = if i > 0 && r.next() < 0.05 {
            out.iter().rev().flatten().next().map_or(Vec3::ZERO, |e| e.p)
        } else {
            Vec3::new(r.next() * 10.0, r.next(), r.next() * 4.0)
        };
        out.push(Some(Emitter { p, n: r.unit(), power: 0.1 + r.next() }));
    }
    out
}

/// Checks every inner node against the lights of its subtree, and that each
/// slot is a leaf exactly once; returns the root's bounds.
fn check(tree: &LightTree, slots: &[Option<Emitter>]) -> Bounds {
    let mut seen = vec![0u32; slots.len()];
    let b = walk(tree, slots, tree.root().expect("a root"), &mut seen);
    assert!(seen.iter().all(|&c| c == 1), "every slot a leaf once");
    b
}

/// The bounds of `c`, checked against every light under it (their
/// positions in its box, their normals in its cone, their power its sum);
/// `lights` gathers the lights under it.
fn walk(tree: &LightTree, slots: &[Option<Emitter>], c: Child, seen: &mut [u32]) -> Bounds {
    let mut lights = Vec::new();
    walk_into(tree, slots, c, seen, &mut lights)
}

fn walk_into(tree: &LightTree, slots: &[Option<Emitter>], c: Child, seen: &mut [u32], lights: &mut Vec<Emitter>) -> Bounds {
    match c {
        Child::Slot(s) => {
            seen[s as usize] += 1;
            let b = Bounds::of(slots[s as usize].as_ref());
            if !b.is_empty() {
                lights.extend(slots[s as usize]);
            }
            b
        }
        Child::Node(i) => {
            let node = tree.node(i);
            let [a, b] = node.children();
            let mut under = Vec::new();
            walk_into(tree, slots, a, seen, &mut under);
            walk_into(tree, slots, b, seen, &mut under);
            let nb = node.bounds;
            for e in &under {
                assert!(nb.lo.cmple(e.p).all() && nb.hi.cmpge(e.p).all(), "node {i}'s box holds {e:?}");
                assert!(nb.cone.contains(e.n.normalize()), "node {i}'s cone {:?} holds the normal {:?}", nb.cone, e.n);
            }
            let sum: f64 = under.iter().map(|e| e.power as f64).sum();
            assert!((nb.power as f64 - sum).abs() <= 1e-5 * sum.max(1e-30), "node {i}'s power {} is its lights' {sum}", nb.power);
            lights.extend(under);
            nb
        }
    }
}

/// Every light's own position, normal and power within the root's bounds.
#[test]
fn every_node_bounds_its_lights() {
    for (n, seed) in [(1, 1), (2, 2), (3, 3), (100, 4), (5000, 5)] {
        let slots = set(n, seed);
        let tree = LightTree::build(&slots).unwrap();
        let root = check(&tree, &slots);
        let total: f32 = slots.iter().flatten().map(|e| e.power).sum();
        assert!((root.power - total).abs() <= 1e-4 * total.max(1e-30), "{n}: {} against {total}", root.power);
        for e in slots.iter().flatten() {
            assert!(root.lo.cmple(e.p).all() && root.hi.cmpge(e.p).all());
            assert!(root.cone.contains(e.n), "{n}: the root's cone holds every normal");
        }
        assert_eq!(tree.nodes().len(), n - 1, "a binary tree over {n} slots");
        assert!(tree.memory_bytes() <= 64 * n.max(1), "{} bytes for {n} slots", tree.memory_bytes());
    }
}

/// Refitting the slots that changed gives what fitting every node again
/// gives, bit for bit; a light in a slot that was empty, and one that
/// left, are refitted in and out.
#[test]
fn a_refit_of_the_moved_slots_equals_fitting_every_node() {
    let mut slots = set(4096, 9);
    let mut tree = LightTree::build(&slots).unwrap();
    let mut r = Rng(77);
    for round in 0..5 {
        let changed: Vec<usize> = (0..16).map(|_| (r.next() * slots.len() as f32) as usize % slots.len()).collect();
        for &s in &changed {
            slots[s] = if r.next() < 0.2 {
                None
            } else {
                Some(Emitter { p: Vec3::new(r.next() * 12.0, r.next() * 3.0, r.next() * 4.0), n: r.unit(), power: r.next() * 5.0 + 0.1 })
            };
        }
        tree.refit(&slots, &changed).unwrap();
        let mut all = tree.clone();
        all.refit(&slots, &(0..slots.len()).collect::<Vec<_>>()).unwrap();
        assert_eq!(tree.nodes(), all.nodes(), "round {round}");
        check(&tree, &slots);
    }
}

/// The same set gives the same tree on one thread and on two.
#[test]
fn the_build_is_the_same_on_one_thread_and_on_two() {
    let slots = set(20_000, 11);
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    let a = pool(1).install(|| LightTree::build(&slots).unwrap());
    let b = pool(2).install(|| LightTree::build(&slots).unwrap());
    assert_eq!(a.nodes(), b.nodes());
    assert_eq!(a.root(), b.root());
}

/// No slot, one slot, only empty slots; a refit of another set's size or
/// of a slot past the end is refused.
#[test]
fn small_and_empty_sets_and_bad_refits() {
    let none = LightTree::build(&[]).unwrap();
    assert_eq!(none.root(), None);
    let one = [Some(Emitter { p: Vec3::ONE, n: Vec3::Y, power: 2.0 })];
    let t = LightTree::build(&one).unwrap();
    assert_eq!(t.root(), Some(Child::Slot(0)));
    assert_eq!(t.bounds(Child::Slot(0), &one).power, 2.0);
    let empty = vec![None; 5];
    let mut t = LightTree::build(&empty).unwrap();
    assert!(check(&t, &empty).is_empty());
    assert_eq!(t.refit(&empty[..4], &[0]), Err(LightTreeError::Slots { built: 5, given: 4 }));
    assert_eq!(t.refit(&empty, &[5]), Err(LightTreeError::Slot { slot: 5, slots: 5 }));
}
