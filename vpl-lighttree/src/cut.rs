//! Stochastic lightcuts (Yuksel, *Stochastic Lightcuts*, HPG 2019) over a
//! [`LightTree`]: the cut at a receiver, chosen by an importance the caller
//! gives, and one light sampled below each cut node.
//!
//! For a receiver x the cut starts at the root, and the node of largest
//! importance is split into its children until the cut holds N nodes (or
//! only lights). Below each cut node C one light y is drawn by walking
//! down, each child taken with probability proportional to its importance
//! at x; p_y is the product of those probabilities. A light's term
//! divided by p_y is then an unbiased estimate of the sum over C's lights,
//! and the sum over the cut one of the sum over all lights, whatever the
//! cut, as long as the importance is positive for every node holding a
//! light that can reach x. The importance is the caller's because what
//! "can reach" means is the receiver's: a one-sided surface, a two-sided
//! one, a medium.

use crate::tree::{Child, LightTree};

impl LightTree {
    /// The cut of at most `n` nodes (at least 1) at a receiver whose
    /// importance of a child is `importance`: from the root, the node of
    /// largest importance is split until `n` nodes are held or none is left
    /// to split. Nodes of no importance (no light of theirs reaches the
    /// receiver) are dropped; ties go to the earlier node, so the cut depends
    /// on the importance alone. Each entry is a child and its importance.
    pub fn cut(&self, n: usize, importance: impl Fn(Child) -> f32) -> Vec<(Child, f32)> {
        let n = n.max(1);
        let mut cut: Vec<(Child, f32)> = Vec::with_capacity(n + 1);
        let Some(root) = self.root() else { return cut };
        let r = importance(root);
        if r > 0.0 {
            cut.push((root, r));
        }
        while cut.len() < n {
            let mut best: Option<usize> = None;
            for (k, &(c, w)) in cut.iter().enumerate() {
                if matches!(c, Child::Node(_)) && best.is_none_or(|b| w > cut[b].1) {
                    best = Some(k);
                }
            }
            let Some(k) = best else { break };
            let Child::Node(i) = cut[k].0 else { break };
            cut.swap_remove(k);
            for c in self.node(i).children() {
                let w = importance(c);
                if w > 0.0 {
                    cut.push((c, w));
                }
            }
        }
        cut
    }

    /// One light below `node`, walking down with each child taken with
    /// probability proportional to `importance`, one number of `u` (in
    /// [0, 1)) a level: its slot and the probability p_y of the walk. `None`
    /// where the walk cannot go on (both children of no importance, or an
    /// importance that is not finite).
    pub fn sample_below(&self, node: Child, importance: impl Fn(Child) -> f32, mut u: impl FnMut() -> f32) -> Option<(u32, f32)> {
        let (mut at, mut p) = (node, 1.0f32);
        while let Child::Node(i) = at {
            let [a, b] = self.node(i).children();
            let (ia, ib) = (importance(a), importance(b));
            let total = ia + ib;
            if total.is_nan() || total <= 0.0 || total.is_infinite() {
                return None;
            }
            let pa = ia / total;
            if u() < pa {
                at = a;
                p *= pa;
            } else {
                at = b;
                p *= 1.0 - pa;
            }
        }
        match at {
            Child::Slot(s) if p > 0.0 => Some((s, p)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{Child, Emitter, LightTree};
    use glam::Vec3;

    fn line(n: usize) -> (LightTree, Vec<Option<Emitter>>) {
        let slots: Vec<Option<Emitter>> =
            (0..n).map(|i| Some(Emitter { p: Vec3::new(i as f32, 0.0, 0.0), n: Vec3::Y, power: 1.0 + i as f32 })).collect();
        (LightTree::build(&slots).unwrap(), slots)
    }

    #[test]
    fn a_cut_covers_every_light_of_importance_once() {
        let (tree, slots) = line(37);
        let importance = |c: Child| tree.bounds(c, &slots).power;
        for n in [1, 2, 5, 16, 37, 100] {
            let cut = tree.cut(n, importance);
            assert_eq!(cut.len(), n.min(37), "cut of {n}");
            // The cut's nodes partition the lights: their powers sum to the root's.
            let total: f32 = cut.iter().map(|&(c, _)| tree.bounds(c, &slots).power).sum();
            assert!((total - (1..=37).sum::<i32>() as f32).abs() < 1e-3, "{total}");
        }
        // Lights of no importance are left out, the rest split.
        let odd = |c: Child| match c {
            Child::Slot(s) => (s % 2) as f32,
            c => tree.bounds(c, &slots).power,
        };
        assert!(tree.cut(37, odd).iter().all(|&(c, w)| w > 0.0 && c != Child::Slot(0)));
    }

    /// A small linear congruential stream of numbers in [0, 1) (the crate has no RNG).
    fn lcg(seed: u64) -> impl FnMut() -> f32 {
        let mut x = seed;
        move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    #[test]
    fn walks_down_in_proportion_to_importance() {
        let (tree, slots) = line(16);
        let root = tree.root().unwrap();
        let total: f32 = (1..=16).map(|i| i as f32).sum();
        // With importance = power, each light's walk probability is its power
        // over the total, so power / p_y is the total for every walk.
        let by_power = |c: Child| tree.bounds(c, &slots).power;
        let mut u = lcg(1);
        for _ in 0..200 {
            let (slot, p) = tree.sample_below(root, by_power, &mut u).unwrap();
            let power = slots[slot as usize].unwrap().power;
            assert!((power / p - total).abs() < 1e-3 * total, "slot {slot}: power {power}, p {p}");
        }
        // With another importance (power over the distance to x = 12), power / p_y
        // is unbiased for the total: the mean of 20 000 walks within 4 standard errors.
        let near = |c: Child| {
            let b = tree.bounds(c, &slots);
            let d = ((b.lo.x + b.hi.x) * 0.5 - 12.0).abs() + (b.hi.x - b.lo.x) * 0.5 + 1.0;
            b.power / d
        };
        let mut u = lcg(7);
        let xs: Vec<f64> = (0..20_000)
            .map(|_| {
                let (slot, p) = tree.sample_below(root, near, &mut u).unwrap();
                (slots[slot as usize].unwrap().power / p) as f64
            })
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let se = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        assert!(se > 0.0 && (mean - total as f64).abs() < 4.0 * se, "mean {mean} ± {se}, total {total}");
        // A node none of whose lights matters cannot be walked.
        assert_eq!(tree.sample_below(root, |_| 0.0, || 0.5), None);
    }
}
