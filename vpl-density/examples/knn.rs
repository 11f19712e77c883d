//! kNN area densities on their own: points on two planes, one sampled four
//! times as densely as the other, and the density each point sees.
//!
//! Run: `cargo run -p vpl-density --example knn`

use glam::Vec3;
use vpl_density::{KnnDensity, rendering_k};

fn main() -> Result<(), vpl_density::DensityError> {
    // A 1 m² floor with 32×32 points (1024 per m²) and, 2 m above it, a
    // 1 m² ceiling with 16×16 points (256 per m²).
    let grid =
        |n: usize, z: f32| (0..n * n).map(move |i| Vec3::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5, 0.0) / n as f32 + Vec3::Z * z);
    let points: Vec<Vec3> = grid(32, 0.0).chain(grid(16, 2.0)).collect();
    let density = KnnDensity::new(&points)?;

    // Eq. (8)'s k for this many points, and each point's density among the others.
    let k = rendering_k(points.len());
    let members = density.members(k);
    let mean = |r: std::ops::Range<usize>| members[r.clone()].iter().sum::<f32>() / r.len() as f32;
    println!("{} points, k = {k}", points.len());
    // p(y) is a probability density (it integrates to 1 over the set's
    // surfaces): N·p(y) counts points per m².
    let n = points.len() as f32;
    println!("floor:   N·p = {:7.1} per m² on average (true 1024; edge points see fewer neighbours)", mean(0..1024) * n);
    println!("ceiling: N·p = {:7.1} per m² on average (true 256)", mean(1024..points.len()) * n);

    // The density of the set at points that are not in it.
    for p in [Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.5, 0.5, 2.0)] {
        println!("N·p at {p}: {:7.1} per m² (k = 16, a point not in the set)", density.at(p, 16)? * n);
    }
    Ok(())
}
