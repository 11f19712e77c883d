//! # vpl-lighttree
//!
//! A light tree over a set of virtual point lights, usable on its own: each
//! node bounds its lights' positions (a box), their normals (a [`Cone`]) and
//! their power, which is what a stochastic lightcut (Yuksel, *Stochastic
//! Lightcuts*, HPG 2019) needs to choose a cut by an importance bound and to
//! sample one light per cut node.
//!
//! The tree is built over the *slots* of a light set, empty ones included,
//! in Morton order of the lights' positions, as a binary radix tree
//! (Karras 2012): every inner node's split is found independently, so the
//! build runs in parallel, and the result is the same bit for bit on any
//! number of threads. When a few lights change (SMC moves at most M_max a
//! frame), [`LightTree::refit`] fits only their ancestors again.
//! [`LightTree::cut`] and [`LightTree::sample_below`] are a stochastic
//! lightcut's two steps, under an importance the caller gives.
//!
//! ```
//! use vpl_lighttree::{Child, Emitter, LightTree};
//! use glam::Vec3;
//!
//! let mut slots: Vec<Option<Emitter>> = (0..8)
//!     .map(|i| Some(Emitter { p: Vec3::new(i as f32, 0.0, 0.0), n: Vec3::Y, power: 1.0 }))
//!     .collect();
//! slots[3] = None;
//! let mut tree = LightTree::build(&slots).unwrap();
//! let Some(Child::Node(root)) = tree.root() else { unreachable!() };
//! assert_eq!(tree.node(root).bounds.power, 7.0);
//! // A light put in the empty slot is refitted in.
//! slots[3] = Some(Emitter { p: Vec3::new(3.0, 5.0, 0.0), n: Vec3::X, power: 2.0 });
//! tree.refit(&slots, &[3]).unwrap();
//! let b = tree.node(root).bounds;
//! assert_eq!((b.power, b.hi.y), (9.0, 5.0));
//! assert!(b.cone.contains(Vec3::X) && b.cone.contains(Vec3::Y));
//! ```

#![warn(missing_docs)]

mod cone;
mod cut;
mod morton;
mod tree;

pub use cone::Cone;
pub use tree::{Bounds, Child, Emitter, LightTree, LightTreeError, Node};
