//! Argument types of the `vpl` command line, parsed from text.

use std::str::FromStr;

/// `--size WxH`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size(pub u32, pub u32);

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("size '{s}' must look like 320x240"))?;
        let w: u32 = w.trim().parse().map_err(|_| format!("size '{s}': width is not a number"))?;
        let h: u32 = h.trim().parse().map_err(|_| format!("size '{s}': height is not a number"))?;
        if w == 0 || h == 0 {
            return Err(format!("size '{s}' must be at least 1x1"));
        }
        let max = vpl_core::camera::MAX_RESOLUTION;
        if w > max || h > max {
            return Err(format!("size '{s}' is larger than {max} on a side"));
        }
        Ok(Size(w, h))
    }
}

/// `--memory-limit`: bytes, or a number with K, M, G, T (powers of 1024;
/// `KiB`, `GB`, … are read the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryArg(pub u64);

impl FromStr for MemoryArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
        let (num, unit) = t.split_at(split);
        let value: f64 = num.trim().parse().map_err(|_| format!("memory limit '{s}' must look like 8G, 512M or a number of bytes"))?;
        let scale: u64 = match unit.trim().to_ascii_uppercase().trim_end_matches('B').trim_end_matches('I') {
            "" => 1,
            "K" => 1 << 10,
            "M" => 1 << 20,
            "G" => 1 << 30,
            "T" => 1 << 40,
            _ => return Err(format!("memory limit '{s}': unknown unit '{unit}' (K, M, G or T)")),
        };
        let bytes = value * scale as f64;
        if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
            return Err(format!("memory limit '{s}' must be positive"));
        }
        Ok(MemoryArg(bytes as u64))
    }
}

/// `--pixel X,Y`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelArg(pub u32, pub u32);

impl FromStr for PixelArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (x, y) = s.split_once(',').ok_or_else(|| format!("pixel '{s}' must look like 12,34"))?;
        let x = x.trim().parse().map_err(|_| format!("pixel '{s}': x is not a non-negative integer"))?;
        let y = y.trim().parse().map_err(|_| format!("pixel '{s}': y is not a non-negative integer"))?;
        Ok(PixelArg(x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sizes_and_clamps() {
        assert_eq!("320x240".parse::<Size>().unwrap(), Size(320, 240));
        assert!("0x10".parse::<Size>().is_err());
        assert!("10".parse::<Size>().is_err());
        // `--clamp` is the renderer's rule, spelled as vpl-render spells it.
        use vpl_render::Clamp;
        assert_eq!("off".parse::<Clamp>().unwrap(), Clamp::Off);
        assert_eq!("2.5".parse::<Clamp>().unwrap(), Clamp::Value(vpl_core::GeometryClamp::new(2.5)));
        let setup = vpl_core::SceneSetup::builtin("cornell").unwrap();
        let (scene, camera) = (&setup.scene, &setup.camera);
        // `area`, the flag's first spelling, still reads as `scene-area`.
        for area in ["area", "scene-area"] {
            let c = area.parse::<Clamp>().unwrap().resolve(100, scene, camera).unwrap();
            assert_eq!(c.g_max, 100.0 / scene.surface_area());
        }
        let view = "auto".parse::<Clamp>().unwrap().resolve(100, scene, camera).unwrap();
        assert_eq!(view, vpl_core::GeometryClamp::for_view(100, scene, camera));
        assert!("areas".parse::<Clamp>().is_err());
        assert!("-1".parse::<Clamp>().is_err());
        assert_eq!("3,4".parse::<PixelArg>().unwrap(), PixelArg(3, 4));
        assert!("3".parse::<PixelArg>().is_err());
    }
}

/// `--frames A..B`: frames A up to, not including, B; `A..` runs to the end
/// of the sequence; a single number is that frame alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramesArg {
    /// First frame.
    pub start: u32,
    /// One past the last frame; `None`: the end of the sequence.
    pub end: Option<u32>,
}

impl FramesArg {
    /// The range within a sequence of `count` frames.
    pub fn range(self, count: u32) -> std::ops::Range<u32> {
        self.start..self.end.unwrap_or(count)
    }
}

impl FromStr for FramesArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let num = |t: &str| t.trim().parse::<u32>().map_err(|_| format!("frames '{s}' must look like 0..90, 30.. or 12"));
        let (start, end) = match s.split_once("..") {
            Some((a, b)) if b.trim().is_empty() => (num(a)?, None),
            Some((a, b)) => (num(a)?, Some(num(b)?)),
            None => {
                let a = num(s)?;
                (a, Some(a.checked_add(1).ok_or_else(|| format!("frames '{s}' is too large"))?))
            }
        };
        if end.is_some_and(|e| e <= start) {
            return Err(format!("frames '{s}' is empty: the end must come after the start"));
        }
        Ok(FramesArg { start, end })
    }
}

#[cfg(test)]
mod frames_tests {
    use super::*;

    #[test]
    fn parses_ranges() {
        assert_eq!("3..9".parse(), Ok(FramesArg { start: 3, end: Some(9) }));
        assert_eq!("5..".parse::<FramesArg>().unwrap().range(20), 5..20);
        assert_eq!("7".parse::<FramesArg>().unwrap().range(20), 7..8);
        assert!("9..3".parse::<FramesArg>().is_err());
        assert!("a..3".parse::<FramesArg>().is_err());
        assert!("3..3".parse::<FramesArg>().is_err());
    }
}
