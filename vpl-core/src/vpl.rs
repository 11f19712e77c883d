//! Virtual point lights and the per-frame set of them.
//!
//! The flux convention every sampler follows (DESIGN.md): a VPL at `y` with
//! normal `n` and RGB `flux` adds to the reflected radiance of a diffuse point
//! `x` with albedo ρ(x)
//!
//! ```text
//! ρ(x)/π · flux · max(0, cos θ_y) · max(0, cos θ_x) / |x − y|² · V(x, y)
//! ```
//!
//! with the geometry factor clamped by [`GeometryClamp`](crate::GeometryClamp).
//! In the SMC paper's notation `flux = L(y) / (N · p(y))` (Hedman et al.
//! 2017, eq. 2 with the camera path fixed): L(y) the exitant radiance of y and
//! p(y) its area density among N VPLs.

use glam::Vec3;

/// A virtual point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Position y.
    pub y: Vec3,
    /// Unit normal of the side that emits (the side light arrived from).
    pub n: Vec3,
    /// RGB flux in the convention above.
    pub flux: Vec3,
    /// Stable identity: seeds the VPL's random streams, so the same VPL draws
    /// the same numbers in every frame.
    pub id: u64,
    /// Scattering vertices between the light and `y`, `y` included (1 = lit
    /// directly). A camera point lit by this VPL ends a path with
    /// `bounce + 1` scattering vertices. 0 when the sampler marginalises over
    /// the light paths that reach `y` (SMC's radiosity estimates).
    pub bounce: u32,
}

impl Vpl {
    /// The unclamped, unshadowed geometry factor max(0, cos θ_y)·max(0, cos θ_x)/|x − y|²
    /// toward a receiver at `x` with normal `n_x`.
    #[inline]
    pub fn geometry(&self, x: Vec3, n_x: Vec3) -> f32 {
        let d = x - self.y;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return 0.0;
        }
        let cos_y = self.n.dot(d);
        let cos_x = -n_x.dot(d);
        if cos_y <= 0.0 || cos_x <= 0.0 { 0.0 } else { cos_y * cos_x / (d2 * d2) }
    }
}

/// The VPLs of a frame in fixed slots, and which slots changed since the
/// previous frame, so that visibility structures rebuild only what moved.
///
/// Two kinds of change are tracked: *changed* (any field differs, flux
/// included) and *moved* (the slot holds a different VPL: position, normal,
/// id or occupancy differ). A sampler that re-weights a VPL in place changes
/// it without moving it, and a shadow map stays valid.
///
/// A slot may be empty: Instant Radiosity leaves one empty when its light
/// path leaves the scene. Estimators treat an empty slot as a VPL of zero
/// flux, so the slot count, not the stored count, is the `I` of eq. (2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VplSet {
    slots: Vec<Option<Vpl>>,
    changed: Vec<bool>,
    moved: Vec<bool>,
    /// Light paths the sampler traced for this frame (for reports).
    pub light_paths: u64,
}

impl VplSet {
    /// `capacity` empty slots, all marked changed.
    pub fn new(capacity: usize) -> VplSet {
        VplSet { slots: vec![None; capacity], changed: vec![true; capacity], moved: vec![true; capacity], light_paths: 0 }
    }

    /// Number of slots (the budget I).
    #[inline]
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether there are no slots.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The VPL in `slot`, if any.
    #[inline]
    pub fn get(&self, slot: usize) -> Option<&Vpl> {
        self.slots.get(slot).and_then(|v| v.as_ref())
    }

    /// Puts `vpl` (or nothing) into `slot`, marking the slot changed when its
    /// content differs from what was there, and moved when it holds another VPL.
    pub fn set(&mut self, slot: usize, vpl: Option<Vpl>) {
        if self.slots[slot] != vpl {
            let same = |a: &Vpl, b: &Vpl| a.y == b.y && a.n == b.n && a.id == b.id;
            if !matches!((&self.slots[slot], &vpl), (Some(a), Some(b)) if same(a, b)) {
                self.moved[slot] = true;
            }
            self.slots[slot] = vpl;
            self.changed[slot] = true;
        }
    }

    /// Resizes to `capacity` slots; new slots are empty and marked changed and moved.
    pub fn resize(&mut self, capacity: usize) {
        self.slots.resize(capacity, None);
        self.changed.resize(capacity, true);
        self.moved.resize(capacity, true);
    }

    /// Starts a new frame: no slot has changed or moved yet.
    pub fn begin_frame(&mut self) {
        self.changed.iter_mut().for_each(|c| *c = false);
        self.moved.iter_mut().for_each(|c| *c = false);
    }

    /// Whether `slot` holds another VPL than at [`VplSet::begin_frame`]
    /// (position, normal, id or occupancy differ; a new flux alone is not a move).
    #[inline]
    pub fn moved(&self, slot: usize) -> bool {
        self.moved[slot]
    }

    /// Number of moved slots.
    pub fn moved_count(&self) -> usize {
        self.moved.iter().filter(|c| **c).count()
    }

    /// Whether `slot` changed since [`VplSet::begin_frame`].
    #[inline]
    pub fn changed(&self, slot: usize) -> bool {
        self.changed[slot]
    }

    /// Number of changed slots.
    pub fn changed_count(&self) -> usize {
        self.changed.iter().filter(|c| **c).count()
    }

    /// Number of occupied slots.
    pub fn stored(&self) -> usize {
        self.slots.iter().filter(|s| s.is_some()).count()
    }

    /// All slots in order.
    #[inline]
    pub fn slots(&self) -> &[Option<Vpl>] {
        &self.slots
    }

    /// Occupied slots with their index.
    pub fn iter(&self) -> impl Iterator<Item = (usize, &Vpl)> {
        self.slots.iter().enumerate().filter_map(|(i, v)| v.as_ref().map(|v| (i, v)))
    }

    /// Sum of the fluxes of all VPLs.
    pub fn total_flux(&self) -> Vec3 {
        self.iter().map(|(_, v)| v.flux).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vpl(x: f32) -> Vpl {
        Vpl { y: Vec3::new(x, 0.0, 0.0), n: Vec3::Y, flux: Vec3::ONE, id: 7, bounce: 1 }
    }

    #[test]
    fn only_real_changes_are_marked() {
        let mut s = VplSet::new(3);
        assert_eq!(s.changed_count(), 3);
        s.set(0, Some(vpl(1.0)));
        s.begin_frame();
        s.set(0, Some(vpl(1.0)));
        s.set(1, None);
        assert_eq!(s.changed_count(), 0);
        s.set(2, Some(vpl(2.0)));
        assert!(s.changed(2) && !s.changed(0));
        assert_eq!(s.moved_count(), 1);
        s.begin_frame();
        s.set(2, Some(Vpl { flux: Vec3::splat(3.0), ..vpl(2.0) }));
        assert!(s.changed(2) && !s.moved(2));
        s.set(2, Some(vpl(2.0)));
        s.set(2, None);
        assert!(s.moved(2) && s.moved_count() == 1);
        s.set(2, Some(vpl(2.0)));
        assert_eq!(s.stored(), 2);
        assert_eq!(s.total_flux(), Vec3::splat(2.0));
    }

    #[test]
    fn geometry_is_one_sided_at_both_ends() {
        let v = vpl(0.0);
        let x = Vec3::new(0.0, 2.0, 0.0);
        assert!((v.geometry(x, -Vec3::Y) - 0.25).abs() < 1e-6);
        assert_eq!(v.geometry(x, Vec3::Y), 0.0);
        assert_eq!(v.geometry(-x, Vec3::Y), 0.0);
    }
}
