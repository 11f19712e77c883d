//! The sequences of the SMC paper's Table 1: five on the built-in scenes
//! and two on real geometry (the scene files `scenes/sponza-dabrovic.toml`
//! and `scenes/city-munich.toml`, whose models live outside the repository
//! and are skipped where they are not), their tracked pixels, and the
//! paper's figures for them.

use std::ops::Range;
use vpl_core::scene_file::LightKeySpec;
use vpl_core::{CoreError, SceneSetup};
use vpl_scene_io::SceneIoError;

/// A tracked pixel: a fixed position in the image (as a fraction of its
/// width and height, so any image size maps it to the same place) and what
/// it is meant to show.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedSpec {
    /// Horizontal position in [0, 1), left to right.
    pub u: f32,
    /// Vertical position in [0, 1), top to bottom.
    pub v: f32,
    /// What the pixel sees over the sequence.
    pub label: &'static str,
}

impl TrackedSpec {
    /// The pixel in a `w`×`h` image.
    pub fn pixel(&self, (w, h): (u32, u32)) -> (u32, u32) {
        (((self.u * w as f32) as u32).min(w - 1), ((self.v * h as f32) as u32).min(h - 1))
    }
}

/// The paper's Table 1 entries of a row, in its column order: MIR, IR, TCAS, SMC ("Ours").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperRow {
    /// Scene of the paper.
    pub scene: &'static str,
    /// Lights as the paper lists them.
    pub lights: &'static str,
    /// Length of the paper's sequence in seconds.
    pub seconds: f32,
    /// Average |E| for MIR, IR, TCAS, SMC.
    pub e: [f64; 4],
    /// Average |E′| for MIR, IR, TCAS, SMC.
    pub e_prime: [f64; 4],
}

/// Methods of the paper's columns, by registry name (MIR as the paper ran
/// it: resampled path-tracer paths).
pub const PAPER_METHODS: [&str; 4] = ["mir-resample", "ir", "tcas", "smc"];

/// One row of Table 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Short name (file names, `--scene`).
    pub id: &'static str,
    /// Scene name in tables: the built-in scene, or the scene file's stem.
    pub scene: &'static str,
    /// The scene file (found by [`crate::scenes::locate`]) of a row on real
    /// geometry; `None`: the built-in scene `scene`.
    pub file: Option<&'static str>,
    /// VPL budget I.
    pub vpls: usize,
    /// The frames `--quick` renders: consecutive frames where the view or
    /// the lights change.
    pub quick_frames: Range<u32>,
    /// The eight tracked pixels.
    pub tracked: [TrackedSpec; 8],
    /// The tracked pixel Fig. 7 plots (index into `tracked`).
    pub fig7_pixel: usize,
    /// Sun keys replacing the scene's static light (the moving-sun row).
    pub sun_keys: &'static [(f32, [f32; 3])],
    /// The paper's row.
    pub paper: PaperRow,
}

const fn px(u: f32, v: f32, label: &'static str) -> TrackedSpec {
    TrackedSpec { u, v, label }
}

/// The street-level pixels of both `courtyard` rows (same camera path).
const COURTYARD_PIXELS: [TrackedSpec; 8] = [
    px(0.50, 0.92, "street just ahead: sunlit or in shadow as the walk goes"),
    px(0.15, 0.70, "left wall, low: lit by the sunlit street"),
    px(0.06, 0.42, "left wall, high: far from the street, indirect only"),
    px(0.80, 0.55, "right-hand facades across the street"),
    px(0.50, 0.62, "end of the street: the square appears"),
    px(0.75, 0.85, "street, right side"),
    px(0.90, 0.75, "right wall, low"),
    px(0.30, 0.55, "left facade, mid height"),
];

/// The moving sun: from low in the east through high south to the west over 24 s.
const MOVING_SUN: [(f32, [f32; 3]); 3] = [(0.0, [0.75, -0.3, -0.6]), (12.0, [0.1, -0.55, -0.83]), (24.0, [-0.6, -0.42, -0.68])];

/// The paper's dynamic Crytek Sponza row, which both `atrium` and `sponza` stand in for.
const PAPER_SPONZA: PaperRow = PaperRow {
    scene: "Crytek Sponza",
    lights: "1 (dynamic)",
    seconds: 20.0,
    e: [0.0288, 0.0215, 0.0352, 0.0962],
    e_prime: [0.0072, 0.0044, 0.0027, 0.0014],
};

/// The paper's Epic Citadel row with a moving sun, which both `courtyard-sun` and `munich` stand in for.
const PAPER_CITADEL_SUN: PaperRow = PaperRow {
    scene: "Epic Citadel",
    lights: "1 (dynamic)",
    seconds: 21.0,
    e: [0.0246, 0.0892, 0.0650, 0.0240],
    e_prime: [0.0129, 0.0323, 0.0198, 0.0071],
};

/// The rows: the paper's five in its order, then the two on real geometry.
pub fn rows() -> Vec<Row> {
    vec![
        Row {
            id: "office",
            scene: "office",
            file: None,
            vpls: 2048,
            quick_frames: 600..608,
            tracked: [
                px(0.50, 0.92, "corridor floor ahead (directly lit)"),
                px(0.40, 0.08, "ceiling between the panels (indirect only)"),
                px(0.30, 0.45, "left corridor wall (directly lit)"),
                px(0.70, 0.40, "right corridor wall (directly lit)"),
                px(0.14, 0.55, "left doorways sweeping past: rooms behind (indirect, revealed)"),
                px(0.88, 0.75, "right doorway floor (indirect)"),
                px(0.50, 0.42, "corridor end: far rooms appear late in the walk"),
                px(0.25, 0.85, "floor by the left wall (indirect corner)"),
            ],
            fig7_pixel: 6,
            sun_keys: &[],
            paper: PaperRow {
                scene: "Soda Hall",
                lights: "14 (static)",
                seconds: 30.0,
                e: [0.0262, 0.0551, 0.0526, 0.0206],
                e_prime: [0.0098, 0.0077, 0.0057, 0.0044],
            },
        },
        Row {
            id: "courtyard",
            scene: "courtyard",
            file: None,
            vpls: 2048,
            quick_frames: 300..308,
            tracked: COURTYARD_PIXELS,
            fig7_pixel: 1,
            sun_keys: &[],
            paper: PaperRow {
                scene: "Epic Citadel",
                lights: "1 (static)",
                seconds: 23.0,
                e: [0.0492, 0.0827, 0.0626, 0.0473],
                e_prime: [0.0241, 0.0364, 0.0227, 0.0222],
            },
        },
        Row {
            id: "maze",
            scene: "maze",
            file: None,
            vpls: 512,
            quick_frames: 300..308,
            tracked: [
                px(0.50, 0.90, "floor ahead (directly lit)"),
                px(0.30, 0.08, "ceiling beside the lamp (indirect only)"),
                px(0.15, 0.45, "left wall"),
                px(0.85, 0.50, "right wall"),
                px(0.50, 0.45, "corridor end: turns come into view"),
                px(0.40, 0.60, "end wall, low"),
                px(0.70, 0.85, "floor, right"),
                px(0.62, 0.30, "end wall, high"),
            ],
            fig7_pixel: 4,
            sun_keys: &[],
            paper: PaperRow {
                scene: "Maze",
                lights: "13 (static)",
                seconds: 22.0,
                e: [0.0287, 0.0869, 0.0380, 0.0221],
                e_prime: [0.0216, 0.0132, 0.0113, 0.0075],
            },
        },
        Row {
            id: "atrium",
            scene: "atrium",
            file: None,
            vpls: 2048,
            quick_frames: 240..248,
            tracked: [
                px(0.50, 0.85, "court floor (the light passes over it)"),
                px(0.50, 0.50, "far end wall"),
                px(0.12, 0.25, "left upper gallery: drapes"),
                px(0.10, 0.60, "left lower gallery, in the arcade's shade (indirect only)"),
                px(0.85, 0.60, "right pillars"),
                px(0.95, 0.45, "right gallery back wall (indirect)"),
                px(0.75, 0.95, "floor near the camera"),
                px(0.25, 0.15, "left upper facade"),
            ],
            fig7_pixel: 3,
            sun_keys: &[],
            paper: PAPER_SPONZA,
        },
        Row {
            id: "courtyard-sun",
            scene: "courtyard",
            file: None,
            vpls: 2048,
            quick_frames: 300..308,
            tracked: COURTYARD_PIXELS,
            fig7_pixel: 1,
            sun_keys: &MOVING_SUN,
            paper: PAPER_CITADEL_SUN,
        },
        Row {
            id: "sponza",
            scene: "sponza-dabrovic",
            file: Some("sponza-dabrovic.toml"),
            vpls: 2048,
            quick_frames: 150..158,
            tracked: [
                px(0.50, 0.85, "nave floor (the light passes over it)"),
                px(0.05, 0.50, "near left arch (indirect)"),
                px(0.30, 0.60, "left arcade, behind the columns (indirect)"),
                px(0.70, 0.45, "right arcade, under the gallery (indirect only)"),
                px(0.50, 0.55, "far end of the nave"),
                px(0.40, 0.25, "left upper gallery"),
                px(0.85, 0.70, "near right pillar, in its own shade"),
                px(0.20, 0.90, "floor under the left arcade (indirect corner)"),
            ],
            fig7_pixel: 3,
            sun_keys: &[],
            paper: PAPER_SPONZA,
        },
        Row {
            id: "munich",
            scene: "city-munich",
            file: Some("city-munich.toml"),
            vpls: 2048,
            quick_frames: 150..158,
            tracked: [
                px(0.50, 0.92, "near roof (directly lit)"),
                px(0.15, 0.55, "roofs on the left"),
                px(0.75, 0.55, "facades on the right, in shadow (indirect only)"),
                px(0.68, 0.30, "the tower"),
                px(0.40, 0.45, "between the blocks"),
                px(0.85, 0.80, "near building on the right, shaded wall"),
                px(0.30, 0.70, "roofs and gaps on the left"),
                px(0.55, 0.60, "central block's facade"),
            ],
            fig7_pixel: 2,
            sun_keys: &[],
            paper: PAPER_CITADEL_SUN,
        },
    ]
}

/// The row called `id`.
pub fn row(id: &str) -> Option<Row> {
    rows().into_iter().find(|r| r.id == id)
}

impl Row {
    /// Why this row cannot run here (its model is not where its scene file
    /// names it), or `None`.
    pub fn missing(&self) -> Option<String> {
        match crate::scenes::locate(self.file?) {
            Ok(path) => crate::scenes::model_missing(&path),
            Err(why) => Some(why),
        }
    }

    /// The scene with this row's animation: the built-in one (with the sun
    /// keys of a moving-sun row added) or the row's scene file.
    pub fn setup(&self) -> Result<SceneSetup, SceneIoError> {
        if let Some(file) = self.file {
            let path = crate::scenes::locate(file).map_err(|why| CoreError::Invalid(format!("sequence {}: {why}", self.id)))?;
            if let Some(why) = crate::scenes::model_missing(&path) {
                return Err(CoreError::Invalid(format!("sequence {}: {why}", self.id)).into());
            }
            return vpl_scene_io::load(&path.to_string_lossy());
        }
        let setup = SceneSetup::builtin(self.scene)?;
        if self.sun_keys.is_empty() {
            return Ok(setup);
        }
        let mut spec = setup.description.sequence.clone().ok_or_else(|| CoreError::Invalid(format!("{} has no sequence", self.scene)))?;
        spec.lights = self.sun_keys.iter().map(|&(t, d)| LightKeySpec { light: 0, t, position: None, direction: Some(d) }).collect();
        Ok(setup.with_sequence(spec)?)
    }

    /// Frames in this row's sequence.
    pub fn frame_count(&self) -> Result<u32, SceneIoError> {
        Ok(self.setup()?.sequence.as_ref().map_or(1, |s| s.frame_count()))
    }

    /// The tracked pixels in a `size` image.
    pub fn pixels(&self, size: (u32, u32)) -> Vec<(u32, u32)> {
        self.tracked.iter().map(|t| t.pixel(size)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_load_and_their_pixels_are_distinct_and_inside() {
        let rows = rows();
        assert_eq!(rows.len(), 7);
        for r in &rows {
            if let Some(why) = r.missing() {
                assert!(r.file.is_some(), "{}: a built-in row is always there", r.id);
                eprintln!("skipped {}: {why}", r.id);
                continue;
            }
            let setup = r.setup().unwrap();
            let n = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
            assert!(r.quick_frames.end <= n && r.quick_frames.len() >= 2, "{}", r.id);
            let mut p = r.pixels((320, 240));
            // Every tracked pixel sees a surface that reflects light (not the sky).
            let camera = setup.camera_at_frame(r.quick_frames.start).unwrap().with_resolution((320, 240)).unwrap();
            for (t, &(x, y)) in r.tracked.iter().zip(&p) {
                let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5));
                assert!(setup.scene.reflecting_hit(&ray).is_some(), "{}: pixel {x},{y} ({}) sees nothing", r.id, t.label);
            }
            p.sort();
            p.dedup();
            assert_eq!(p.len(), 8, "{}", r.id);
            assert!(r.fig7_pixel < 8);
        }
        // The moving sun turns; the static one does not.
        let sun = |id: &str, f: u32| row(id).unwrap().setup().unwrap().frame(f).unwrap().0.lights.clone();
        assert_ne!(sun("courtyard-sun", 0), sun("courtyard-sun", 300));
        assert_eq!(sun("courtyard", 0), sun("courtyard", 300));
    }
}
