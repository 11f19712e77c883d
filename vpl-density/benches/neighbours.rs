//! The searches of SMC's flux cells, at the sizes of one office frame
//! (2048 VPLs, 32,768 candidate hits, about 10,700 probes to place): each
//! hit's nearest other hit (line 6's weights), and each probe's nearest
//! VPL on its own surface (normals within 60°), over points on the six
//! faces of a room, where a probe near a corner has VPLs of another
//! surface nearest. The queries run on all threads, one walk each or
//! together.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use rayon::prelude::*;
use vpl_density::KnnDensity;

/// `n` points on the faces of a 10 × 3 × 8 room, with their normals
/// (inward), from a xorshift stream seeded by `seed`.
fn room(n: usize, seed: u64) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let size = Vec3::new(10.0, 3.0, 8.0);
    (0..n)
        .map(|_| {
            let (face, u, v) = ((next() * 6.0) as usize % 6, next(), next());
            let (axis, high) = (face / 2, face % 2 == 1);
            let mut p = Vec3::ZERO;
            let mut nrm = Vec3::ZERO;
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            p[a] = u * size[a];
            p[b] = v * size[b];
            p[axis] = if high { size[axis] } else { 0.0 };
            nrm[axis] = if high { -1.0 } else { 1.0 };
            (p, nrm)
        })
        .unzip()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("flux cells");
    g.sample_size(20);
    let (hits, _) = room(32_768, 7);
    g.bench_function("tree over 32768 hits", |b| b.iter(|| KnnDensity::new(&hits).unwrap().within(Vec3::ZERO, 0.0)));
    g.bench_function("members' nearest, 32768 hits", |b| b.iter(|| KnnDensity::new(&hits).unwrap().member_nearest()));
    let (sites, site_n) = room(2048, 11);
    let (probes, probe_n) = room(10_700, 13);
    let tree = KnnDensity::new(&sites).unwrap();
    tree.member_nearest();
    g.bench_function("nearest on the same surface, 10700 probes of 2048 VPLs", |b| {
        b.iter(|| probes.par_iter().zip(&probe_n).filter_map(|(&p, &n)| tree.nearest_accepted(p, None, |i| site_n[i].dot(n) > 0.5)).count())
    });
    g.bench_function("nearest on the same surface, 10700 probes of 2048 VPLs at once", |b| {
        b.iter(|| tree.nearest_accepted_each(&probes, |q, i| site_n[i].dot(probe_n[q]) > 0.5).into_iter().flatten().count())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
