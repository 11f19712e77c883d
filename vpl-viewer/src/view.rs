//! What the view shows: a side's image, a reference or the difference
//! against it, or one of its G-buffer channels; two sides split down the
//! middle; the VPLs splatted over them, the interleaving pattern, a picked
//! VPL. Pure functions of the frames, so every picture the window shows can
//! be checked without a window.

use glam::Vec3;
use vpl_core::image::{linear_to_srgb, luminance, reinhard};
use vpl_core::{Camera, GBuffer, Image, VplSet};

/// The image or a G-buffer channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Channel {
    /// The frame's radiance, tone-mapped (Reinhard, sRGB).
    #[default]
    Image,
    /// The reference accumulating while the camera stands still (the path
    /// tracer), tone-mapped as the image is.
    Reference,
    /// The frame minus the reference: red where the frame is brighter, blue
    /// where it is darker, full colour at a luminance difference of
    /// 1/exposure × the reference's mean luminance.
    Difference,
    /// Diffuse albedo ρ.
    Albedo,
    /// Shading normals, mapped from [−1, 1] to [0, 1].
    Normals,
    /// Distance along the camera ray, relative to the farthest surface seen.
    Depth,
}

impl Channel {
    /// Every channel, in menu order.
    pub const ALL: [Channel; 6] =
        [Channel::Image, Channel::Reference, Channel::Difference, Channel::Albedo, Channel::Normals, Channel::Depth];

    /// Its name in menus and scripts.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Image => "image",
            Channel::Reference => "reference",
            Channel::Difference => "difference",
            Channel::Albedo => "albedo",
            Channel::Normals => "normals",
            Channel::Depth => "depth",
        }
    }

    /// The channel of a name.
    pub fn parse(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// What is drawn over the view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Overlay {
    /// Nothing.
    #[default]
    Off,
    /// Each VPL the camera sees (not hidden behind the G-buffer's surface) as
    /// a 3×3 splat coloured by its flux, relative to the set's median (blue
    /// dim, red bright); those that moved this frame ringed in white.
    Vpls,
    /// The interleaving pattern: pixel (x, y) is of class 4·(y mod 4) +
    /// (x mod 4) and shades with subset c of the VPLs only
    /// ([`vpl_shading::InterleavedShader`]); each class tinted with its own
    /// hue. With a picked VPL, the pixels of its subset's class are lit and
    /// the others dimmed: the pixels that VPL reaches.
    Interleave,
}

impl Overlay {
    /// Every overlay, in menu order.
    pub const ALL: [Overlay; 3] = [Overlay::Off, Overlay::Vpls, Overlay::Interleave];

    /// Its name in menus and scripts.
    pub fn name(self) -> &'static str {
        match self {
            Overlay::Off => "off",
            Overlay::Vpls => "vpls",
            Overlay::Interleave => "interleave",
        }
    }

    /// The overlay of a name.
    pub fn parse(name: &str) -> Option<Overlay> {
        Overlay::ALL.into_iter().find(|o| o.name() == name)
    }
}

/// A VPL picked in the view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pick {
    /// The side it belongs to (0 left, 1 right).
    pub side: usize,
    /// Its slot in that side's set.
    pub slot: usize,
    /// The interleaving class whose pixels shade with it (`None` when the
    /// side shades every VPL at every pixel).
    pub class: Option<usize>,
}

/// How the view is drawn.
#[derive(Clone, Copy, Debug)]
pub struct Look<'a> {
    /// The image or a channel.
    pub channel: Channel,
    /// What is drawn over it.
    pub overlay: Overlay,
    /// Exposure of the tone mapping (and the difference's scale).
    pub exposure: f32,
    /// The reference, at the sides' size (the reference and difference
    /// channels show black without one).
    pub reference: Option<&'a Image>,
    /// A picked VPL, ringed in magenta.
    pub picked: Option<Pick>,
}

impl Look<'_> {
    /// The image, no overlay, exposure 1, no reference, nothing picked.
    pub fn image() -> Look<'static> {
        Look { channel: Channel::Image, overlay: Overlay::Off, exposure: 1.0, reference: None, picked: None }
    }
}

/// One side of the view: a frame and the camera it was rendered from.
#[derive(Clone, Copy)]
pub struct SideFrame<'a> {
    /// Radiance.
    pub image: &'a Image,
    /// The frame's G-buffer (same size as the image).
    pub gbuffer: &'a GBuffer,
    /// The VPLs the frame was shaded with.
    pub vpls: &'a VplSet,
    /// The camera it was rendered from.
    pub camera: &'a Camera,
}

/// The view as the window shows it.
#[derive(Clone, Debug)]
pub struct Composite {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Display pixels (sRGB, RGBA, row-major).
    pub rgba: Vec<u8>,
    /// What the display pixels show before tone mapping (radiance, or the
    /// channel's values), overlay excluded: a screenshot's EXR.
    pub hdr: Image,
    /// First column of the right side, when split.
    pub split_x: Option<u32>,
}

/// Colour of the split line and of the ring of a VPL that moved.
pub const MARK: [u8; 4] = [255, 255, 255, 255];

/// Colour of the ring around a picked VPL.
pub const PICKED: [u8; 4] = [255, 0, 255, 255];

/// Half-width of the split line in pixels.
const SPLIT_HALF_WIDTH: u32 = 1;

/// The left side over the whole view, or split down the middle with the
/// right side's right half. Both sides must be the same size.
pub fn compose(left: SideFrame, right: Option<SideFrame>, look: &Look) -> Composite {
    let Look { channel, overlay, exposure, picked, .. } = *look;
    let (w, h) = (left.image.width, left.image.height);
    let reference = look.reference.filter(|r| r.width == w && r.height == h);
    let ref_scale = reference.map_or(1.0, difference_scale);
    let split_x = right.map(|_| w / 2);
    let far = |g: &GBuffer| g.samples.iter().map(|s| s.depth).filter(|d| d.is_finite()).fold(0.0f32, f32::max).max(1e-6);
    let far_l = far(left.gbuffer);
    let far_r = right.map_or(far_l, |r| far(r.gbuffer));
    let mut hdr = Image::new(w, h);
    let mut rgba = vec![0u8; (w * h * 4) as usize];
    for y in 0..h {
        for x in 0..w {
            let (side, far) = match (right, split_x) {
                (Some(r), Some(s)) if x >= s => (r, far_r),
                _ => (left, far_l),
            };
            let i = (y * w + x) as usize;
            let g = side.gbuffer.samples.get(i);
            let (value, display) = match channel {
                Channel::Image => {
                    let c = side.image.data.get(i).copied().unwrap_or(Vec3::ZERO);
                    (c, linear_to_srgb(reinhard(c * exposure)))
                }
                Channel::Reference => {
                    let c = reference.and_then(|r| r.data.get(i)).copied().unwrap_or(Vec3::ZERO);
                    (c, linear_to_srgb(reinhard(c * exposure)))
                }
                Channel::Difference => match reference.and_then(|r| r.data.get(i)) {
                    Some(r) => {
                        let d = side.image.data.get(i).copied().unwrap_or(Vec3::ZERO) - *r;
                        let t = (luminance(d) / ref_scale * exposure).clamp(-1.0, 1.0);
                        let c = if t >= 0.0 { Vec3::new(t, 0.15 * t, 0.0) } else { Vec3::new(0.0, -0.15 * t, -t) };
                        (d, linear_to_srgb(c))
                    }
                    None => (Vec3::ZERO, Vec3::ZERO),
                },
                Channel::Albedo => {
                    let a = g.map_or(Vec3::ZERO, |g| g.albedo);
                    (a, linear_to_srgb(a))
                }
                Channel::Normals => {
                    let n = g.filter(|g| g.depth.is_finite()).map_or(Vec3::ZERO, |g| g.n);
                    let v = if n == Vec3::ZERO { Vec3::ZERO } else { n * 0.5 + 0.5 };
                    (n, v)
                }
                Channel::Depth => {
                    let d = g.map_or(f32::INFINITY, |g| g.depth);
                    let v = if d.is_finite() { 1.0 - d / far } else { 0.0 };
                    (Vec3::splat(if d.is_finite() { d } else { 0.0 }), Vec3::splat(v))
                }
            };
            hdr.set(x, y, value);
            let px = [display.x, display.y, display.z].map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
            rgba[i * 4..i * 4 + 4].copy_from_slice(&[px[0], px[1], px[2], 255]);
        }
    }
    let ranges = [(left, 0, split_x.unwrap_or(w)), (right.unwrap_or(left), split_x.unwrap_or(w), w)];
    match overlay {
        Overlay::Off => {}
        Overlay::Vpls => {
            for (side, x0, x1) in ranges {
                splat_vpls(&mut rgba, w, h, side, x0, x1);
            }
        }
        Overlay::Interleave => {
            for (k, (_, x0, x1)) in ranges.into_iter().enumerate() {
                let lit = picked.filter(|p| p.side == k).and_then(|p| p.class);
                tint_classes(&mut rgba, w, h, x0, x1, lit);
            }
        }
    }
    if let Some(p) = picked
        && let Some((side, x0, x1)) = ranges.get(p.side).copied()
        && let Some(v) = side.vpls.get(p.slot)
        && let Some((px, py)) = seen(side, v.y)
    {
        let (x, y) = (px as i64, py as i64);
        for d in -4..=4i64 {
            for (a, b) in [(x + d, y - 4), (x + d, y + 4), (x - 4, y + d), (x + 4, y + d)] {
                if a >= x0 as i64 && a < x1 as i64 && b >= 0 && b < h as i64 {
                    let i = ((b as u32 * w + a as u32) * 4) as usize;
                    rgba[i..i + 4].copy_from_slice(&PICKED);
                }
            }
        }
    }
    if let Some(s) = split_x {
        for y in 0..h {
            for x in s.saturating_sub(SPLIT_HALF_WIDTH)..(s + SPLIT_HALF_WIDTH).min(w) {
                let i = ((y * w + x) * 4) as usize;
                rgba[i..i + 4].copy_from_slice(&MARK);
            }
        }
    }
    Composite { width: w, height: h, rgba, hdr, split_x }
}

/// The difference channel's scale: the reference's mean luminance.
pub(crate) fn difference_scale(reference: &Image) -> f32 {
    let m = reference.data.iter().map(|c| luminance(*c) as f64).sum::<f64>() / reference.data.len().max(1) as f64;
    (m as f32).max(1e-6)
}

/// The median luminance of a set's lit VPLs' fluxes, which the overlay
/// colours against; `None` when none is lit.
pub(crate) fn flux_median(vpls: &VplSet) -> Option<f32> {
    let mut lum: Vec<f32> = vpls.iter().map(|(_, v)| luminance(v.flux)).filter(|l| *l > 0.0).collect();
    if lum.is_empty() {
        return None;
    }
    lum.sort_by(f32::total_cmp);
    Some(lum[lum.len() / 2].max(f32::MIN_POSITIVE))
}

/// The overlay's colour of a VPL of flux `flux`: log₁₀ of its luminance
/// over the median, −2 … +2, onto the [`heat`] ramp.
pub(crate) fn flux_colour(flux: Vec3, median: f32) -> [u8; 4] {
    heat(((luminance(flux) / median).max(1e-6).log10() + 2.0) / 4.0)
}

/// A colour for `t` in [0, 1]: blue, cyan, green, yellow, red.
pub fn heat(t: f32) -> [u8; 4] {
    let t = t.clamp(0.0, 1.0);
    let stops =
        [Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.0, 0.9, 1.0), Vec3::new(0.1, 1.0, 0.2), Vec3::new(1.0, 0.95, 0.0), Vec3::new(1.0, 0.1, 0.0)];
    let f = t * (stops.len() - 1) as f32;
    let i = (f as usize).min(stops.len() - 2);
    let c = stops[i].lerp(stops[i + 1], f - i as f32);
    [(c.x * 255.0) as u8, (c.y * 255.0) as u8, (c.z * 255.0) as u8, 255]
}

/// Hue of interleaving class `c` of [`vpl_shading::CLASSES`], linear RGB.
fn class_hue(c: usize) -> Vec3 {
    // Neighbouring classes get hues far apart (7 is prime to 16).
    let h = ((c * 7) % vpl_shading::CLASSES) as f32 / vpl_shading::CLASSES as f32 * 6.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    match h as u32 {
        0 => Vec3::new(1.0, x, 0.0),
        1 => Vec3::new(x, 1.0, 0.0),
        2 => Vec3::new(0.0, 1.0, x),
        3 => Vec3::new(0.0, x, 1.0),
        4 => Vec3::new(x, 0.0, 1.0),
        _ => Vec3::new(1.0, 0.0, x),
    }
}

/// Tints columns `x0..x1` by interleaving class; with `lit`, that class's
/// pixels are kept and marked, the others dimmed.
fn tint_classes(rgba: &mut [u8], w: u32, h: u32, x0: u32, x1: u32, lit: Option<usize>) {
    for y in 0..h {
        for x in x0..x1 {
            let c = vpl_shading::InterleavedShader::class(x, y);
            let i = ((y * w + x) * 4) as usize;
            let px = Vec3::new(rgba[i] as f32, rgba[i + 1] as f32, rgba[i + 2] as f32) / 255.0;
            let out = match lit {
                Some(l) if l == c => px.lerp(Vec3::new(1.0, 0.0, 1.0), 0.35),
                Some(_) => px * 0.25,
                None => px.lerp(linear_to_srgb(class_hue(c)), 0.45),
            };
            for (k, v) in [out.x, out.y, out.z].into_iter().enumerate() {
                rgba[i + k] = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        }
    }
}

/// Where `y` falls in `side`'s image, when the camera sees it (it is not
/// behind the surface its pixel sees).
fn seen(side: SideFrame, y: Vec3) -> Option<(f32, f32)> {
    let (w, h) = (side.image.width, side.image.height);
    let (px, py) = side.camera.project(y)?;
    if !(px >= 0.0 && py >= 0.0 && px < w as f32 && py < h as f32) {
        return None;
    }
    let (x, yy) = (px as u32, py as u32);
    let surface = side.gbuffer.samples.get((yy * w + x) as usize).map_or(f32::INFINITY, |g| g.depth);
    let dist = (y - side.camera.origin).length();
    (dist <= surface * 1.02 + 1e-3 * surface.max(1.0)).then_some((px, py))
}

/// The slot of the visible VPL of `side` nearest to pixel `(x, y)`, within
/// `radius` pixels.
pub fn pick_vpl(side: SideFrame, x: f32, y: f32, radius: f32) -> Option<usize> {
    side.vpls
        .iter()
        .filter_map(|(slot, v)| seen(side, v.y).map(|(px, py)| (slot, (px - x).powi(2) + (py - y).powi(2))))
        .filter(|(_, d2)| *d2 <= radius * radius)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(slot, _)| slot)
}

/// Σ(frame) / Σ(reference) and the root-mean-square difference relative to
/// the reference's mean, over pixels and channels.
pub fn against_reference(image: &Image, reference: &Image) -> Option<(f64, f64)> {
    if image.width != reference.width || image.height != reference.height || image.data.is_empty() {
        return None;
    }
    let (mut a, mut r, mut sq) = (0.0f64, 0.0f64, 0.0f64);
    for (p, q) in image.data.iter().zip(&reference.data) {
        a += p.element_sum() as f64;
        r += q.element_sum() as f64;
        let d = *p - *q;
        sq += d.dot(d) as f64;
    }
    let n = (image.data.len() * 3) as f64;
    (r > 0.0).then(|| (a / r, (sq / n).sqrt() / (r / n)))
}

/// Splats `side`'s visible VPLs into columns `x0..x1` of the view.
fn splat_vpls(rgba: &mut [u8], w: u32, h: u32, side: SideFrame, x0: u32, x1: u32) {
    let Some(median) = flux_median(side.vpls) else { return };
    let mut put = |x: i64, y: i64, c: [u8; 4]| {
        if x >= x0 as i64 && x < x1 as i64 && y >= 0 && y < h as i64 {
            let i = ((y as u32 * w + x as u32) * 4) as usize;
            rgba[i..i + 4].copy_from_slice(&c);
        }
    };
    for (slot, v) in side.vpls.iter() {
        // Hidden behind the surface the pixel sees: not splatted.
        let Some((px, py)) = seen(side, v.y) else { continue };
        let (x, y) = (px as u32, py as u32);
        let c = flux_colour(v.flux, median);
        let (x, y) = (x as i64, y as i64);
        for dy in -1..=1 {
            for dx in -1..=1 {
                put(x + dx, y + dy, c);
            }
        }
        if side.vpls.moved(slot) {
            for d in -2..=2 {
                put(x + d, y - 2, MARK);
                put(x + d, y + 2, MARK);
                put(x - 2, y + d, MARK);
                put(x + 2, y + d, MARK);
            }
        }
    }
}

/// The frame-to-frame change Σ|ΔL| / ΣL over pixels and channels (what the
/// SMC paper's |E′| measures, here of one frame against the one before).
pub fn temporal_change(previous: &Image, current: &Image) -> Option<f64> {
    if previous.width != current.width || previous.height != current.height {
        return None;
    }
    let (mut diff, mut sum) = (0.0f64, 0.0f64);
    for (a, b) in previous.data.iter().zip(&current.data) {
        diff += ((*b - *a).abs().element_sum()) as f64;
        sum += b.element_sum().max(0.0) as f64;
    }
    (sum > 0.0).then_some(diff / sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::{FovAxis, GSample, Vpl};

    fn scene_frame(value: Vec3) -> (Image, GBuffer, Camera) {
        let (w, h) = (32, 16);
        let camera = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, FovAxis::X, (w, h)).unwrap();
        let mut image = Image::new(w, h);
        image.data.iter_mut().for_each(|p| *p = value);
        let s = GSample { p: Vec3::ZERO, n: Vec3::Z, ng: Vec3::Z, albedo: Vec3::splat(0.5), emitted: Vec3::ZERO, material: 0, depth: 5.0 };
        let gbuffer = GBuffer { width: w, height: h, samples: vec![s; (w * h) as usize], pixel_angle: 0.01, eye: camera.origin };
        (image, gbuffer, camera)
    }

    fn px(c: &Composite, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * c.width + x) * 4) as usize;
        c.rgba[i..i + 4].try_into().unwrap()
    }

    #[test]
    fn a_split_shows_each_side_on_its_half_with_a_line_between() {
        let (a, ga, cam) = scene_frame(Vec3::splat(0.2));
        let (b, gb, _) = scene_frame(Vec3::splat(2.0));
        let none = VplSet::new(0);
        let l = SideFrame { image: &a, gbuffer: &ga, vpls: &none, camera: &cam };
        let r = SideFrame { image: &b, gbuffer: &gb, vpls: &none, camera: &cam };
        let c = compose(l, Some(r), &Look { channel: Channel::Image, overlay: Overlay::Off, ..Look::image() });
        assert_eq!(c.split_x, Some(16));
        assert_eq!(px(&c, 16, 5), MARK);
        assert!(px(&c, 3, 5)[0] < px(&c, 28, 5)[0]);
        assert_eq!(c.hdr.get(3, 5), Vec3::splat(0.2));
        assert_eq!(c.hdr.get(28, 5), Vec3::splat(2.0));
        let alone = compose(l, None, &Look { channel: Channel::Image, overlay: Overlay::Off, ..Look::image() });
        assert_eq!(alone.split_x, None);
        assert_eq!(px(&alone, 28, 5), px(&alone, 3, 5));
    }

    #[test]
    fn visible_vpls_are_splatted_and_hidden_ones_are_not() {
        let (a, g, cam) = scene_frame(Vec3::splat(0.2));
        let mut set = VplSet::new(2);
        let vpl = |y: Vec3, id| Vpl { y, n: Vec3::Z, flux: Vec3::ONE, id, bounce: 1 };
        set.set(0, Some(vpl(Vec3::ZERO, 1)));
        // Behind the surface at depth 5 the G-buffer sees.
        set.set(1, Some(vpl(Vec3::new(1.0, 0.0, -3.0), 2)));
        let l = SideFrame { image: &a, gbuffer: &g, vpls: &set, camera: &cam };
        let off = compose(l, None, &Look { channel: Channel::Image, overlay: Overlay::Off, ..Look::image() });
        let on = compose(l, None, &Look { channel: Channel::Image, overlay: Overlay::Vpls, ..Look::image() });
        let (cx, cy) = cam.project(Vec3::ZERO).unwrap();
        assert_ne!(px(&on, cx as u32, cy as u32), px(&off, cx as u32, cy as u32));
        // The first frame marks every slot moved: ringed.
        assert_eq!(px(&on, cx as u32 + 2, cy as u32), MARK);
        let (hx, hy) = cam.project(Vec3::new(1.0, 0.0, -3.0)).unwrap();
        assert_eq!(px(&on, hx as u32, hy as u32), px(&off, hx as u32, hy as u32));
        assert_eq!(on.hdr.data, off.hdr.data);
    }

    #[test]
    fn channels_show_the_gbuffer() {
        let (a, g, cam) = scene_frame(Vec3::splat(0.2));
        let none = VplSet::new(0);
        let l = SideFrame { image: &a, gbuffer: &g, vpls: &none, camera: &cam };
        let n = compose(l, None, &Look { channel: Channel::Normals, overlay: Overlay::Off, ..Look::image() });
        assert_eq!(px(&n, 4, 4), [128, 128, 255, 255]);
        let d = compose(l, None, &Look { channel: Channel::Depth, overlay: Overlay::Off, ..Look::image() });
        assert_eq!(d.hdr.get(4, 4), Vec3::splat(5.0));
        assert_eq!(Channel::parse("albedo"), Some(Channel::Albedo));
    }

    #[test]
    fn the_difference_is_red_where_brighter_and_blue_where_darker() {
        let (a, g, cam) = scene_frame(Vec3::splat(0.2));
        let (mut reference, _, _) = scene_frame(Vec3::splat(0.2));
        reference.set(1, 1, Vec3::splat(0.4));
        reference.set(2, 1, Vec3::splat(0.1));
        let none = VplSet::new(0);
        let l = SideFrame { image: &a, gbuffer: &g, vpls: &none, camera: &cam };
        let look = Look { channel: Channel::Difference, reference: Some(&reference), ..Look::image() };
        let d = compose(l, None, &look);
        assert_eq!(px(&d, 0, 0), [0, 0, 0, 255], "no difference is black");
        let darker = px(&d, 1, 1);
        let brighter = px(&d, 2, 1);
        assert!(darker[2] > 100 && darker[0] == 0, "{darker:?}");
        assert!(brighter[0] > 100 && brighter[2] == 0, "{brighter:?}");
        assert_eq!(d.hdr.get(1, 1), Vec3::splat(-0.2));
        let r = compose(l, None, &Look { channel: Channel::Reference, reference: Some(&reference), ..Look::image() });
        assert_eq!(r.hdr.get(1, 1), Vec3::splat(0.4));
        // Without a reference both show black, never a panic.
        let none_yet = compose(l, None, &Look { channel: Channel::Difference, ..Look::image() });
        assert!(none_yet.rgba.chunks(4).all(|p| p == [0, 0, 0, 255]));
        let (ratio, rmse) = against_reference(&a, &reference).unwrap();
        assert!(ratio < 1.0 && rmse > 0.0);
        assert_eq!(against_reference(&a, &a), Some((1.0, 0.0)));
    }

    #[test]
    fn the_interleaving_pattern_repeats_every_four_pixels_and_a_pick_lights_its_class() {
        let (a, g, cam) = scene_frame(Vec3::splat(0.2));
        let mut set = VplSet::new(1);
        set.set(0, Some(Vpl { y: Vec3::ZERO, n: Vec3::Z, flux: Vec3::ONE, id: 1, bounce: 1 }));
        let l = SideFrame { image: &a, gbuffer: &g, vpls: &set, camera: &cam };
        let c = compose(l, None, &Look { overlay: Overlay::Interleave, ..Look::image() });
        assert_eq!(px(&c, 1, 2), px(&c, 5, 6));
        assert_ne!(px(&c, 1, 2), px(&c, 2, 2));
        let (cx, cy) = cam.project(Vec3::ZERO).unwrap();
        assert_eq!(pick_vpl(l, cx + 3.0, cy, 5.0), Some(0));
        assert_eq!(pick_vpl(l, cx + 9.0, cy, 5.0), None);
        let picked = Look { overlay: Overlay::Interleave, picked: Some(Pick { side: 0, slot: 0, class: Some(5) }), ..Look::image() };
        let p = compose(l, None, &picked);
        // Class 5 is (1, 1) mod 4: lit; class 0 dimmed.
        assert!(px(&p, 1, 1)[0] > px(&p, 0, 0)[0]);
        assert_eq!(px(&p, (cx as u32) + 4, cy as u32), PICKED, "the picked VPL is ringed");
    }

    #[test]
    fn temporal_change_is_relative() {
        let (a, _, _) = scene_frame(Vec3::splat(1.0));
        let (b, _, _) = scene_frame(Vec3::splat(1.5));
        assert!((temporal_change(&a, &b).unwrap() - 0.5 / 1.5).abs() < 1e-9);
        assert_eq!(temporal_change(&a, &a), Some(0.0));
    }
}
