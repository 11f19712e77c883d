//! Linear RGB f32 images: EXR read/write, PNG previews (Reinhard + sRGB), atomic writes.

use crate::error::{CoreError, Result};
use glam::Vec3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A linear-RGB image, row-major, pixel (0,0) top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width·height` pixels, row by row from the top.
    pub data: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Image {
        Image { width, height, data: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Pixel (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.data[(y * self.width + x) as usize]
    }

    /// Sets pixel (x, y).
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        self.data[(y * self.width + x) as usize] = v;
    }

    /// Mean over all pixels, per channel (f64 accumulation).
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.data {
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        let n = self.data.len().max(1) as f64;
        [s[0] / n, s[1] / n, s[2] / n]
    }

    #[cfg(feature = "formats")]
    /// Reads the RGB channels of the first layer of an OpenEXR file.
    pub fn read_exr(path: impl AsRef<Path>) -> Result<Image> {
        use exr::prelude::*;
        let path = path.as_ref();
        if let Err(e) = std::fs::metadata(path) {
            return Err(CoreError::Read { path: path.into(), source: e });
        }
        let img = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                |res, _| Self::new(res.width() as u32, res.height() as u32),
                |img: &mut Self, pos, (r, g, b): (f32, f32, f32)| img.set(pos.x() as u32, pos.y() as u32, Vec3::new(r, g, b)),
            )
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .map_err(|e| CoreError::Image(format!("{}: {e}", path.display())))?;
        Ok(img.layer_data.channel_data.pixels)
    }

    #[cfg(feature = "formats")]
    /// Writes a 32-bit float RGB OpenEXR file, atomically.
    pub fn write_exr(&self, path: impl AsRef<Path>) -> Result<()> {
        use exr::prelude::*;
        let path = path.as_ref();
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            LayerAttributes::named("rgb"),
            Encoding::SMALL_LOSSLESS,
            SpecificChannels::rgb(|pos: Vec2<usize>| {
                let p = self.data[pos.y() * self.width as usize + pos.x()];
                (p.x, p.y, p.z)
            }),
        );
        let mut bytes = std::io::Cursor::new(Vec::new());
        exr::image::Image::from_layer(layer)
            .write()
            .non_parallel()
            .to_buffered(&mut bytes)
            .map_err(|e| CoreError::Write { path: path.into(), reason: e.to_string() })?;
        write_atomic(path, &bytes.into_inner())
    }

    #[cfg(feature = "formats")]
    /// Writes an 8-bit sRGB PNG of the Reinhard-tone-mapped image, atomically.
    /// `exposure` scales radiance before tone mapping.
    pub fn write_png(&self, path: impl AsRef<Path>, exposure: f32) -> Result<()> {
        let path = path.as_ref();
        let mut rgb = Vec::with_capacity(self.data.len() * 3);
        for p in &self.data {
            let c = linear_to_srgb(reinhard(*p * exposure));
            rgb.extend([c.x, c.y, c.z].map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
        }
        write_png_rgb8(path, self.width, self.height, &rgb)
    }
}

#[cfg(feature = "formats")]
/// Writes 8-bit RGB pixels (row-major, 3 bytes a pixel) as a PNG, atomically.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    let err = |e: png::EncodingError| CoreError::Write { path: path.into(), reason: e.to_string() };
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(err)?;
        w.write_image_data(rgb).map_err(err)?;
    }
    write_atomic(path, &out)
}

/// Luminance (Rec. 709 / sRGB primaries).
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Reinhard's global operator on luminance, L/(1+L), applied by scaling the
/// colour (Reinhard et al. 2002, eq. 3 with L_white = ∞).
#[inline]
pub fn reinhard(c: Vec3) -> Vec3 {
    let l = luminance(c);
    if l <= 0.0 { Vec3::ZERO } else { c / (1.0 + l) }
}

/// The sRGB transfer function (IEC 61966-2-1), per channel.
#[inline]
pub fn linear_to_srgb(c: Vec3) -> Vec3 {
    let f = |v: f32| {
        let v = v.max(0.0);
        if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
    };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

/// The path of the PNG preview written beside `path` (same stem, `.png`).
pub fn preview_path(path: &Path) -> PathBuf {
    path.with_extension("png")
}

/// Writes `bytes` to `path` atomically: a temporary file in the same
/// directory, flushed, then renamed over `path`. On failure nothing is left behind.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let err = |reason: String| CoreError::Write { path: path.into(), reason };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(err(format!("directory {} does not exist", dir.display())));
    }
    let name = path.file_name().ok_or_else(|| err("no file name".into()))?;
    let tmp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(err(e.to_string()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(feature = "formats")]
    fn exr_round_trip_is_exact() {
        let dir = std::env::temp_dir().join(format!("vpl-core-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut img = Image::new(5, 3);
        for (i, p) in img.data.iter_mut().enumerate() {
            *p = Vec3::new(i as f32 * 0.25, 1e-7 * i as f32, 1000.5 + i as f32);
        }
        let path = dir.join("a.exr");
        img.write_exr(&path).unwrap();
        assert_eq!(Image::read_exr(&path).unwrap(), img);
        img.write_png(dir.join("a.png"), 1.0).unwrap();
        assert!(img.write_exr(dir.join("missing/a.exr")).is_err());
        assert!(!dir.join("missing").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reinhard_maps_into_unit_range() {
        let c = reinhard(Vec3::splat(1.0));
        assert!((c.x - 0.5).abs() < 1e-6);
        assert_eq!(reinhard(Vec3::ZERO), Vec3::ZERO);
        assert!((linear_to_srgb(Vec3::ONE).x - 1.0).abs() < 1e-6);
    }
}
