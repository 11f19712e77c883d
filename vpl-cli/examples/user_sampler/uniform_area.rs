//! A sampler written outside the toolkit: VPLs uniform by surface area.
//!
//! Slot i holds a point y drawn with density p(y) = 1/A over all surfaces
//! (area A), on a side chosen with probability 1/2 where surfaces reflect on
//! both sides, and carries the flux of vpl-core's convention,
//! `flux = L(y) / (I · p(y)) = L(y) · A / I` (× 2 for the side), with L(y) the
//! radiosity estimate the renderer's backend provides. The points depend
//! only on the seed and the slot, so they never move: when the lights
//! change, only fluxes change and shadow maps are kept.
//!
//! It reads one parameter, `radiosity-paths` (paths per estimate, 16).

use vpl_sampling::vpl_core::distribution::Distribution1D;
use vpl_sampling::vpl_core::sampling::uniform_triangle;
use vpl_sampling::vpl_core::scene::LightingKey;
use vpl_sampling::vpl_core::{Frame, ParamKey, Purpose, SharedEstimator, Stats, Vpl, VplSampler, VplSet, stream};
use vpl_sampling::{Params, SamplerContext, SamplerEntry, SamplingError};

/// The stream purpose of the points (any value the toolkit does not use).
const UNIFORM_AREA: Purpose = Purpose(1001);

/// VPLs uniform by area, weighted by radiosity.
pub struct UniformArea {
    set: VplSet,
    radiosity: SharedEstimator,
    lighting: Option<LightingKey>,
    estimates: usize,
}

impl UniformArea {
    /// The parameters it reads.
    pub const KEYS: &'static [ParamKey] = &[ParamKey { key: "radiosity-paths", default: "16", about: "paths per radiosity estimate" }];

    /// The registry entry: `uniform-area`.
    pub fn entry() -> SamplerEntry {
        SamplerEntry::new("uniform-area", "VPLs uniform by surface area, weighted by radiosity (a user-defined sampler)", Self::build)
            .with_keys(Self::KEYS)
    }

    fn build(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
        cx.needs_vpls("uniform-area")?;
        cx.needs_indirect("uniform-area")?;
        let param = |source| SamplingError::Param { name: "uniform-area".into(), source };
        let paths: u32 = p.count_or("radiosity-paths", 16, 1).map_err(param)?;
        let radiosity = cx.radiosity(paths, cx.budget.radiosity_bounces());
        Ok(Box::new(UniformArea { set: VplSet::new(cx.budget.vpls), radiosity, lighting: None, estimates: 0 }))
    }
}

impl VplSampler for UniformArea {
    fn name(&self) -> &'static str {
        "uniform-area"
    }

    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        self.set.begin_frame();
        self.estimates = 0;
        let scene = frame.scene;
        let key = LightingKey::of(scene);
        if self.lighting.as_ref() == Some(&key) {
            return &self.set;
        }
        let triangles = &scene.geometry.triangles;
        let areas: Vec<f32> = triangles.iter().map(|t| t.area).collect();
        let Some(by_area) = Distribution1D::new(&areas) else { return &self.set };
        let area = scene.surface_area();
        let sides = if scene.two_sided { 2.0 } else { 1.0 };
        let n = self.set.len();
        // Points and seeds from the slot alone: the same VPLs in every frame.
        let points: Vec<_> = (0..n)
            .map(|slot| {
                let mut rng = stream(frame.seed, 0, UNIFORM_AREA, slot as u64);
                let (tri, _) = by_area.sample(rng.next_f32());
                let (b1, b2) = uniform_triangle(rng.next_f32(), rng.next_f32());
                let y = scene.surface_point(tri as u32, b1, b2);
                let y = if scene.two_sided && rng.next_f32() < 0.5 { y.facing(-y.ng) } else { y };
                (y, rng.next_u32() as u64)
            })
            .collect();
        let radiance = self.radiosity.radiosity_many(scene, &points);
        for (slot, ((y, seed), l)) in points.iter().zip(radiance).enumerate() {
            let flux = l * (area * sides / n as f32);
            self.set.set(slot, Some(Vpl { y: y.p, n: y.n, flux, id: *seed, bounce: 0 }));
        }
        self.estimates = n;
        self.lighting = Some(key);
        &self.set
    }

    fn stats(&self) -> Stats {
        Stats::new().count("stored", self.set.stored()).count("moved", self.set.moved_count()).count("estimates", self.estimates)
    }
}
