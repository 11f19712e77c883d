//! Bitmap textures (PNG, JPEG) as the scene readers use them: decoded under
//! limits decided before the decoder allocates, and reduced to their mean
//! linear colour (the toolkit's materials are one colour each).
//!
//! The image's header is read first: more than [`crate::input::MAX_IMAGE_PIXELS`]
//! pixels, or a decoded size beyond the memory limit, is refused before any
//! pixel is decoded. The mean is taken over the decoded texels in place
//! (no second, wider copy), so the peak is the decoded image itself.

use crate::input::MAX_IMAGE_PIXELS;
use glam::{DVec3, Vec3};
use std::io::Cursor;

/// The most bytes one decoded bitmap may take when no memory limit is given
/// (4 GiB: a 16384² RGBA image of 16-bit channels is 2 GiB).
pub const MAX_DECODED_BYTES: u64 = 4 << 30;

/// How one channel of a texel is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    /// 8-bit unsigned normalised.
    U8,
    /// 16-bit unsigned normalised, in the machine's byte order.
    U16,
    /// 32-bit float, in the machine's byte order.
    F32,
}

impl Depth {
    /// Bytes per channel.
    pub fn bytes(self) -> usize {
        match self {
            Depth::U8 => 1,
            Depth::U16 => 2,
            Depth::F32 => 4,
        }
    }
}

/// Texels as stored: `channels` (1 grey, 2 grey and alpha, 3 RGB, 4 RGBA)
/// of `depth` each.
#[derive(Clone, Copy, Debug)]
pub struct Texels<'a> {
    /// The texels, row after row.
    pub bytes: &'a [u8],
    /// Channels per texel (1 to 4).
    pub channels: usize,
    /// How each channel is stored.
    pub depth: Depth,
}

/// How the texels' alpha weighs them in the mean.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AlphaUse {
    /// Texels whose alpha is under this are left out (glTF's `MASK`).
    pub cutoff: Option<f32>,
    /// Each texel counts by its alpha (glTF's `BLEND`).
    pub blend: bool,
}

/// The mean linear RGB of `t`: integer channels decoded from sRGB when
/// `srgb`, float channels always linear. `None` when no texel counts.
pub fn mean_colour(t: Texels, srgb: bool, alpha: AlphaUse) -> Option<Vec3> {
    let channels = t.channels.clamp(1, 4);
    let size = channels * t.depth.bytes();
    // 8-bit sRGB through a table.
    let lut: Vec<f32> = (0..256).map(|v| if srgb { vpl_core::image::srgb_to_linear(v as f32 / 255.0) } else { v as f32 / 255.0 }).collect();
    let raw = |x: &[u8], c: usize| -> f32 {
        match t.depth {
            Depth::U8 => x[c] as f32 / 255.0,
            Depth::U16 => u16::from_ne_bytes([x[2 * c], x[2 * c + 1]]) as f32 / 65535.0,
            Depth::F32 => f32::from_ne_bytes([x[4 * c], x[4 * c + 1], x[4 * c + 2], x[4 * c + 3]]),
        }
    };
    let linear = |x: &[u8], c: usize| -> f32 {
        match t.depth {
            Depth::U8 => lut[x[c] as usize],
            Depth::U16 if srgb => vpl_core::image::srgb_to_linear(raw(x, c)),
            _ => raw(x, c),
        }
    };
    let (mut sum, mut weight) = (DVec3::ZERO, 0.0f64);
    for x in t.bytes.chunks_exact(size) {
        let rgb = match channels {
            1 | 2 => Vec3::splat(linear(x, 0)),
            _ => Vec3::new(linear(x, 0), linear(x, 1), linear(x, 2)),
        };
        let a = match channels {
            2 => raw(x, 1),
            4 => raw(x, 3),
            _ => 1.0,
        };
        let w = match alpha.cutoff {
            Some(c) if a < c => continue,
            _ if alpha.blend => a.clamp(0.0, 1.0),
            _ => 1.0,
        };
        if rgb.is_finite() {
            sum += rgb.as_dvec3() * w as f64;
            weight += w as f64;
        }
    }
    (weight > 0.0).then(|| (sum / weight).as_vec3())
}

/// Decodes a PNG or JPEG held in `bytes` (`format` when the container says
/// which; else guessed from the bytes). The decoded image may take at most
/// `memory_limit` bytes (or [`MAX_DECODED_BYTES`]) and have at most
/// [`MAX_IMAGE_PIXELS`] pixels; both are checked on the header, before the
/// decoder allocates. Errors are one line naming the reason, never pixels.
pub fn decode(bytes: &[u8], format: Option<image::ImageFormat>, memory_limit: Option<u64>) -> Result<image::DynamicImage, String> {
    let reader = |bytes| -> Result<image::ImageReader<Cursor<&[u8]>>, String> {
        let mut r = image::ImageReader::new(Cursor::new(bytes));
        match format {
            Some(f) => r.set_format(f),
            None => r = r.with_guessed_format().map_err(|e| e.to_string())?,
        }
        match r.format() {
            Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => Ok(r),
            _ => Err("it is neither PNG nor JPEG".into()),
        }
    };
    let (w, h) = reader(bytes)?.into_dimensions().map_err(|e| format!("cannot decode it ({e})"))?;
    let pixels = w as u64 * h as u64;
    if pixels > MAX_IMAGE_PIXELS {
        return Err(format!("it is {w}×{h}, more than the {MAX_IMAGE_PIXELS} pixels an image may have"));
    }
    let limit = memory_limit.unwrap_or(MAX_DECODED_BYTES).min(MAX_DECODED_BYTES);
    let mut r = reader(bytes)?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(limit);
    r.limits(limits);
    r.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => format!("decoding its {w}×{h} pixels takes more than the memory limit of {limit} bytes"),
        e => format!("cannot decode it ({e})"),
    })
}

/// The texels of a decoded image as [`mean_colour`] reads them.
pub fn texels(img: &image::DynamicImage) -> Texels<'_> {
    use image::ColorType as C;
    let (channels, depth) = match img.color() {
        C::L8 => (1, Depth::U8),
        C::La8 => (2, Depth::U8),
        C::Rgb8 => (3, Depth::U8),
        C::Rgba8 => (4, Depth::U8),
        C::L16 => (1, Depth::U16),
        C::La16 => (2, Depth::U16),
        C::Rgb16 => (3, Depth::U16),
        C::Rgba16 => (4, Depth::U16),
        C::Rgb32F => (3, Depth::F32),
        C::Rgba32F => (4, Depth::F32),
        // Colour types added to `image` later: read as opaque grey bytes
        // rather than misread.
        _ => (1, Depth::U8),
    };
    Texels { bytes: img.as_bytes(), channels, depth }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, rgba: [u8; 4]) -> Vec<u8> {
        let img = image::RgbaImage::from_pixel(w, h, image::Rgba(rgba));
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn the_mean_is_linear_and_the_memory_limit_holds_before_decoding() {
        let bytes = png(64, 32, [188, 188, 188, 255]);
        let img = decode(&bytes, None, None).unwrap();
        let m = mean_colour(texels(&img), true, AlphaUse::default()).unwrap();
        // sRGB 188/255 is linear 0.5029.
        assert!((m.x - 0.5029).abs() < 1e-3, "{m}");
        let raw = mean_colour(texels(&img), false, AlphaUse::default()).unwrap();
        assert!((raw.x - 188.0 / 255.0).abs() < 1e-6);
        // 64 × 32 × 4 = 8 KiB decoded: a 4 KiB limit refuses it by name.
        let e = decode(&bytes, None, Some(4096)).unwrap_err();
        assert!(e.contains("memory limit of 4096 bytes"), "{e}");
        assert!(decode(&bytes, None, Some(8192)).is_ok());
        let e = decode(b"not an image at all", None, None).unwrap_err();
        assert!(e.contains("neither PNG nor JPEG"), "{e}");
        // A texture whose every texel is masked has no mean.
        let clear = decode(&png(2, 2, [255, 0, 0, 10]), None, None).unwrap();
        assert!(mean_colour(texels(&clear), true, AlphaUse { cutoff: Some(0.5), blend: false }).is_none());
    }
}
