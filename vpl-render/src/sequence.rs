//! Rendering a range of frames of a scene's sequence with one renderer,
//! recording tracked pixels: `vpl sequence`.

use crate::error::RenderError;
use crate::frame::StageTimings;
use crate::renderer::Renderer;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;
use vpl_core::glam::Vec3;
use vpl_core::image::{luminance, write_atomic};
use vpl_core::{Image, SceneSetup, Stats};

/// One rendered frame of a sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceFrame {
    /// Frame index in the scene's sequence.
    pub index: u32,
    /// Time in seconds.
    pub time: f32,
    /// Radiance at each tracked pixel.
    pub tracked: Vec<Vec3>,
    /// Stage timings.
    pub timings: StageTimings,
    /// VPL slots that moved since the previous frame.
    pub moved: usize,
    /// Shadow maps (or other per-VPL structures) rebuilt.
    pub rebuilt: usize,
    /// The sampler's statistics of the frame.
    pub stats: Stats,
}

/// Checks that `frames` is a non-empty range inside `setup`'s sequence (a
/// scene without one has frame 0 only).
pub fn check_frames(setup: &SceneSetup, frames: &Range<u32>) -> Result<(), RenderError> {
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    if frames.start >= frames.end || frames.end > count {
        return Err(RenderError::Frames { start: frames.start, end: frames.end, count });
    }
    Ok(())
}

/// Eight pixels spread over a `w`×`h` image: a ring of six around the
/// centre at a third of the half-size, plus the centre and a point low in
/// the image (where floors are).
pub fn default_tracked_pixels(w: u32, h: u32) -> Vec<(u32, u32)> {
    let (cx, cy) = (w as f32 * 0.5, h as f32 * 0.5);
    let mut px = vec![(cx, cy), (cx, h as f32 * 0.85)];
    for i in 0..6 {
        let a = i as f32 * std::f32::consts::TAU / 6.0 + 0.3;
        px.push((cx + a.cos() * w as f32 * 0.3, cy + a.sin() * h as f32 * 0.3));
    }
    px.into_iter().map(|(x, y)| ((x as u32).min(w - 1), (y as u32).min(h - 1))).collect()
}

/// Renders frames `frames` of `setup`'s sequence (the still scene when it
/// has none: then only frame 0 exists) at `size`, keeping the renderer's
/// state from frame to frame. With `out`, writes `tracked.csv` and
/// `frames.csv` there at the end. `on_frame` sees each frame and its image
/// as it is done (`vpl sequence` writes the images there: `vpl-scene-io`'s
/// EXR and PNG); its error ends the run.
pub fn run_sequence(
    setup: &SceneSetup,
    frames: Range<u32>,
    size: Option<(u32, u32)>,
    renderer: &mut Renderer,
    tracked: &[(u32, u32)],
    out: Option<&Path>,
    on_frame: &mut dyn FnMut(&SequenceFrame, &Image) -> Result<(), RenderError>,
) -> Result<Vec<SequenceFrame>, RenderError> {
    check_frames(setup, &frames)?;
    let fps = setup.sequence.as_ref().map_or(30.0, |s| s.fps);
    let mut done = Vec::with_capacity(frames.len());
    for f in frames {
        let (scene, mut camera) = setup.frame(f)?;
        if let Some(s) = size {
            camera = camera.with_resolution(s)?;
        }
        let (w, h) = camera.resolution;
        if let Some(&(x, y)) = tracked.iter().find(|(x, y)| *x >= w || *y >= h) {
            return Err(RenderError::Pixel(x, y, w, h));
        }
        let time = f as f32 / fps;
        let r = renderer.render(&scene, &camera, f as u64, time)?;
        let frame = SequenceFrame {
            index: f,
            time,
            tracked: tracked.iter().map(|&(x, y)| r.image.data[(y * w + x) as usize]).collect(),
            timings: r.timings,
            moved: r.moved,
            rebuilt: r.visibility.rebuilt,
            stats: r.sampler_stats.clone(),
        };
        on_frame(&frame, &r.image)?;
        done.push(frame);
    }
    if let Some(dir) = out {
        write_atomic(&dir.join("tracked.csv"), tracked_csv(tracked, &done).as_bytes())?;
        write_atomic(&dir.join("frames.csv"), frames_csv(&done).as_bytes())?;
    }
    Ok(done)
}

/// One row per frame and tracked pixel: frame, time, pixel, RGB, luminance.
pub fn tracked_csv(tracked: &[(u32, u32)], frames: &[SequenceFrame]) -> String {
    let mut s = String::from("frame,time,pixel,x,y,r,g,b,luminance\n");
    for f in frames {
        for (i, (&(x, y), c)) in tracked.iter().zip(&f.tracked).enumerate() {
            let _ = writeln!(s, "{},{:.6},{i},{x},{y},{},{},{},{}", f.index, f.time, c.x, c.y, c.z, luminance(*c));
        }
    }
    s
}

/// One row per frame: stage milliseconds, moved VPLs and rebuilt maps,
/// then one column per sampler statistic (the keys of all frames, in the
/// order first seen; empty where a frame lacks one).
pub fn frames_csv(frames: &[SequenceFrame]) -> String {
    let mut keys: Vec<&'static str> = Vec::new();
    for k in frames.iter().flat_map(|f| f.stats.keys()) {
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut s = String::from("frame,time,total_ms,gbuffer_ms,sampling_ms,visibility_ms,shading_ms,direct_ms,moved,rebuilt");
    for k in &keys {
        let _ = write!(s, ",sampler_{k}");
    }
    s.push('\n');
    for f in frames {
        let t = f.timings;
        let _ = write!(
            s,
            "{},{:.6},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{}",
            f.index, f.time, t.total_ms, t.gbuffer_ms, t.sampling_ms, t.visibility_ms, t.shading_ms, t.direct_ms, f.moved, f.rebuilt
        );
        for k in &keys {
            match f.stats.stat(k) {
                Some(v) => {
                    let _ = write!(s, ",{v}");
                }
                None => s.push(','),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracked_pixels_are_inside_and_distinct() {
        for (w, h) in [(320, 240), (640, 360), (16, 9)] {
            let p = default_tracked_pixels(w, h);
            assert_eq!(p.len(), 8);
            assert!(p.iter().all(|&(x, y)| x < w && y < h));
            let mut q = p.clone();
            q.sort();
            q.dedup();
            assert_eq!(q.len(), 8, "{p:?}");
        }
    }
}
