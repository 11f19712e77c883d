//! Building the tree over 64K and 1M lights, and refitting 16 moved slots
//! of the 1M tree (issue targets: ≤ 0.3 s and ≤ 1 ms on 2 cores).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use vpl_lighttree::{Emitter, LightTree};

fn lights(n: usize) -> Vec<Option<Emitter>> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let n = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vec3::Y);
            Some(Emitter { p: Vec3::new(next() * 30.0, next() * 10.0, next() * 20.0), n, power: next() + 0.01 })
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("light tree");
    g.sample_size(10);
    for n in [65_536usize, 1 << 20] {
        let slots = lights(n);
        g.bench_function(format!("build {n}"), |b| b.iter(|| LightTree::build(&slots).unwrap()));
    }
    let mut slots = lights(1 << 20);
    let mut tree = LightTree::build(&slots).unwrap();
    let moved: Vec<usize> = (0..16).map(|i| i * 65_519 % slots.len()).collect();
    let mut k = 0u32;
    g.bench_function("refit 16 of 1M", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            for &s in &moved {
                if let Some(e) = slots[s].as_mut() {
                    e.p.y = (k % 7) as f32;
                }
            }
            tree.refit(&slots, &moved).unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
