use vpl_core::glam::Vec3;
fn main() {
    let spp: u32 = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(64);
    let vs = vpl_bench::validation::validate_cornell(std::path::Path::new("tests/data/cornell-box"), spp, 1, &|_| {}).unwrap();
    for v in &vs {
        let mut img = v.comparison.z_image.clone();
        for p in img.data.iter_mut() { *p = if p.x > 2.935 { Vec3::new(10.0, 0.0, 0.0) } else { Vec3::splat(p.x / 2.935 * 0.3) }; }
        img.write_png(format!("/tmp/z_{}.png", v.mode), 1.0).unwrap();
        // signed mean diff over failing pixels
        let (mut pos, mut neg) = (0, 0);
        for i in 0..v.ours.0.data.len() { if v.comparison.z_image.data[i].x > 2.935 { if v.ours.0.data[i].x + v.ours.0.data[i].y > v.theirs.0.data[i].x + v.theirs.0.data[i].y { pos += 1 } else { neg += 1 } } }
        println!("{} pass {:.4} fail+ {} fail- {}", v.mode, v.comparison.pass_rate, pos, neg);
    }
}
