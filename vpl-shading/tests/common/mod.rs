//! What the unbiasedness tests of the stochastic shaders share: the image
//! and 8×8-block means of a frame, and the z-test of many frames' means
//! against the exhaustive image's.

use vpl_core::Image;
use vpl_core::image::luminance;

const BLOCK: u32 = 8;

/// Luminance means of the image and of its 8×8 blocks.
pub fn means(img: &Image) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.data.len() as f64];
    for by in (0..h).step_by(BLOCK as usize) {
        for bx in (0..w).step_by(BLOCK as usize) {
            let (mut s, mut k) = (0.0, 0);
            for y in by..(by + BLOCK).min(h) {
                for x in bx..(bx + BLOCK).min(w) {
                    s += luminance(img.data[(y * w + x) as usize]) as f64;
                    k += 1;
                }
            }
            out.push(s / k as f64);
        }
    }
    out
}

/// Asserts that the mean over `frames` of each entry (the image, then the
/// blocks) lies within 4 standard errors of `truth`'s; an entry the same
/// in every frame must equal it. Answers whether any entry varied.
pub fn assert_unbiased(label: &str, truth: &[f64], frames: &[Vec<f64>]) -> bool {
    let mut varied = false;
    for (k, &t) in truth.iter().enumerate() {
        let xs: Vec<f64> = frames.iter().map(|f| f[k]).collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        let what = if k == 0 { "the image".to_string() } else { format!("block {}", k - 1) };
        if se == 0.0 {
            assert!((mean - t).abs() <= 1e-6 * t.abs().max(1e-12), "{label}, {what}: {mean} every frame against {t}");
            continue;
        }
        varied = true;
        let z = (mean - t) / se;
        if k == 0 {
            eprintln!("{label}: image mean {mean:.5} ± {se:.5} against {t:.5} (z {z:+.2})");
        }
        assert!(z.abs() <= 4.0, "{label}, {what}: {mean:.6} ± {se:.6} against {t:.6}, z = {z:.2}");
    }
    varied
}
