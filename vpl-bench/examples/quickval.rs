fn main() {
    let spp: u32 = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(64);
    let t = std::time::Instant::now();
    let vs = vpl_bench::validation::validate_cornell(std::path::Path::new("tests/data/cornell-box"), spp, 1, &|m| eprintln!("{m}")).unwrap();
    println!("{}", vpl_bench::validation::report_markdown(&vs, spp));
    for v in &vs { println!("{} {:.2} Mpaths/s", v.mode, 65536.0 * spp as f64 / v.seconds / 1e6); }
    eprintln!("{:?}", t.elapsed());
}
