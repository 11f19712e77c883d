use vpl_core::Image;
fn main() {
    let d = std::path::Path::new("tests/data/cornell-box");
    for stem in ["reference_direct_d2", "reference_path_d5", "reference_indirect"] {
        let a = Image::read_exr(d.join(format!("{stem}.exr"))).unwrap();
        let s = Image::read_exr(d.join(format!("{stem}_stderr.exr"))).unwrap();
        for (x, y) in [(128u32, 36u32), (120, 37), (140, 38), (128, 128), (10, 250)] {
            println!("{stem} ({x},{y}) {:?} se {:?}", a.get(x, y), s.get(x, y));
        }
    }
}
