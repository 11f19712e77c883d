//! Image files: OpenEXR (32-bit float RGB, read and written) and PNG
//! previews (Reinhard + sRGB, 8 bits), written atomically.

use crate::error::{Result, SceneIoError};
use std::path::Path;
use vpl_core::CoreError;
use vpl_core::Image;
#[cfg(feature = "exr")]
use vpl_core::glam::Vec3;
use vpl_core::image::{linear_to_srgb, reinhard, write_atomic};

/// EXR and PNG files of an [`Image`].
pub trait ImageFile: Sized {
    /// Reads the RGB channels of the first layer of an OpenEXR file.
    ///
    /// The file must be a regular file of at most
    /// [`crate::input::MAX_IMAGE_BYTES`]; its header is read first and every
    /// layer it declares must hold at most [`crate::input::MAX_IMAGE_PIXELS`]
    /// pixels, so a header claiming a 10⁹ × 10⁹ window is refused before any
    /// allocation. A NaN or infinite pixel is an error naming the pixel.
    fn read_exr(path: impl AsRef<Path>) -> Result<Self>;

    /// Decodes the bytes of an OpenEXR file as [`ImageFile::read_exr`]
    /// does; `path` names it in messages.
    fn decode_exr(bytes: &[u8], path: &Path) -> Result<Self>;

    /// Writes a 32-bit float RGB OpenEXR file, atomically.
    fn write_exr(&self, path: impl AsRef<Path>) -> vpl_core::Result<()>;

    /// The bytes of a 32-bit float RGB OpenEXR file of this image.
    fn encode_exr(&self) -> std::result::Result<Vec<u8>, String>;

    /// Writes an 8-bit sRGB PNG of the Reinhard-tone-mapped image,
    /// atomically. `exposure` scales radiance before tone mapping.
    fn write_png(&self, path: impl AsRef<Path>, exposure: f32) -> vpl_core::Result<()>;

    /// The PNG file [`ImageFile::write_png`] writes, in memory.
    fn encode_png(&self, exposure: f32) -> std::result::Result<Vec<u8>, String>;
}

impl ImageFile for Image {
    fn read_exr(path: impl AsRef<Path>) -> Result<Image> {
        let path = path.as_ref();
        let bytes = crate::input::read_bytes(path, crate::input::MAX_IMAGE_BYTES)?;
        Self::decode_exr(&bytes, path)
    }

    #[cfg(feature = "exr")]
    fn decode_exr(bytes: &[u8], path: &Path) -> Result<vpl_core::Image> {
        use exr::prelude::*;
        let bad = |reason: String| SceneIoError::from(CoreError::Image(format!("{}: {reason}", path.display())));
        let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false).map_err(|e| bad(e.to_string()))?;
        for h in meta.headers.iter() {
            let (w, hgt) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
            if w.saturating_mul(hgt) > crate::input::MAX_IMAGE_PIXELS || w > u32::MAX as u64 || hgt > u32::MAX as u64 {
                return Err(bad(format!("its header declares a {w} × {hgt} layer, more than {} pixels", crate::input::MAX_IMAGE_PIXELS)));
            }
        }
        let img = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                |res, _| vpl_core::Image::new(res.width() as u32, res.height() as u32),
                |img: &mut vpl_core::Image, pos, (r, g, b): (f32, f32, f32)| img.set(pos.x() as u32, pos.y() as u32, Vec3::new(r, g, b)),
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .map_err(|e| bad(e.to_string()))?;
        let img = img.layer_data.channel_data.pixels;
        if let Some(i) = img.data.iter().position(|p| !p.is_finite()) {
            let p = img.data[i];
            let (x, y) = (i as u32 % img.width.max(1), i as u32 / img.width.max(1));
            return Err(SceneIoError::from(CoreError::BadValue {
                what: format!("{} pixel ({x}, {y})", path.display()),
                reason: format!("{} {} {} is not finite", p.x, p.y, p.z),
            }));
        }
        Ok(img)
    }

    #[cfg(not(feature = "exr"))]
    fn decode_exr(_bytes: &[u8], path: &Path) -> Result<Image> {
        Err(SceneIoError::from(CoreError::Image(format!("{}: reading EXR files needs vpl-scene-io's `exr` feature", path.display()))))
    }

    fn write_exr(&self, path: impl AsRef<Path>) -> vpl_core::Result<()> {
        let path = path.as_ref();
        let bytes = self.encode_exr().map_err(|reason| CoreError::Write { path: path.into(), reason })?;
        write_atomic(path, &bytes)
    }

    #[cfg(feature = "exr")]
    fn encode_exr(&self) -> std::result::Result<Vec<u8>, String> {
        use exr::prelude::*;
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
        exr::image::Image::from_layer(layer).write().non_parallel().to_buffered(&mut bytes).map_err(|e| e.to_string())?;
        Ok(bytes.into_inner())
    }

    #[cfg(not(feature = "exr"))]
    fn encode_exr(&self) -> std::result::Result<Vec<u8>, String> {
        Err("writing EXR files needs vpl-scene-io's `exr` feature".into())
    }

    fn write_png(&self, path: impl AsRef<Path>, exposure: f32) -> vpl_core::Result<()> {
        let path = path.as_ref();
        let png = self.encode_png(exposure).map_err(|reason| CoreError::Write { path: path.into(), reason })?;
        write_atomic(path, &png)
    }

    fn encode_png(&self, exposure: f32) -> std::result::Result<Vec<u8>, String> {
        let mut rgb = Vec::with_capacity(self.data.len() * 3);
        for p in &self.data {
            let c = linear_to_srgb(reinhard(*p * exposure));
            rgb.extend([c.x, c.y, c.z].map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
        }
        encode_png_rgb8(self.width, self.height, &rgb)
    }
}

/// Writes 8-bit RGB pixels (row-major, 3 bytes a pixel) as a PNG, atomically.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> vpl_core::Result<()> {
    let out = encode_png_rgb8(width, height, rgb).map_err(|reason| CoreError::Write { path: path.into(), reason })?;
    write_atomic(path, &out)
}

/// The PNG file of 8-bit RGB pixels (row-major, 3 bytes a pixel).
#[cfg(feature = "png")]
pub fn encode_png_rgb8(width: u32, height: u32, rgb: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let err = |e: png::EncodingError| e.to_string();
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(err)?;
        w.write_image_data(rgb).map_err(err)?;
    }
    Ok(out)
}

/// Without the `png` feature there is no PNG writer.
#[cfg(not(feature = "png"))]
pub fn encode_png_rgb8(_width: u32, _height: u32, _rgb: &[u8]) -> std::result::Result<Vec<u8>, String> {
    Err("writing PNG files needs vpl-scene-io's `png` feature".into())
}

#[cfg(all(test, feature = "exr", feature = "png"))]
mod tests {
    use super::*;

    #[test]
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
    fn hostile_exr_headers_and_pixels_are_refused() {
        let mut img = Image::new(2, 2);
        img.data.fill(Vec3::splat(0.5));
        let bytes = img.encode_exr().unwrap();
        assert_eq!(Image::decode_exr(&bytes, Path::new("a.exr")).unwrap(), img);
        // A header that claims a 10⁹ × 10⁹ data window (box2i: xmin ymin xmax ymax).
        let mut huge = bytes.clone();
        let tag = b"dataWindow\0box2i\0";
        let at = huge.windows(tag.len()).position(|w| w == tag).unwrap() + tag.len() + 4;
        for (k, v) in [0i32, 0, 1_000_000_000, 1_000_000_000].into_iter().enumerate() {
            huge[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        let e = Image::decode_exr(&huge, Path::new("huge.exr")).unwrap_err().to_string();
        assert!(e.contains("huge.exr"), "{e}");
        // A NaN pixel.
        img.data[3] = Vec3::new(0.0, f32::NAN, 0.0);
        let e = Image::decode_exr(&img.encode_exr().unwrap(), Path::new("n.exr")).unwrap_err().to_string();
        assert!(e.contains("n.exr pixel (1, 1)") && e.contains("not finite"), "{e}");
        // Garbage and truncation.
        assert!(Image::decode_exr(b"not an exr", Path::new("g.exr")).is_err());
        assert!(Image::decode_exr(&bytes[..bytes.len() / 2], Path::new("t.exr")).is_err());
    }
}
