//! The toolkit's own samplers as registry entries: each reads its settings
//! from the parameters with its crate's `from_params`.

use crate::registry::{MemoryPart, SamplerContext, SamplerEntry, SamplingError};
use vpl_core::{Budget, ParamError, Params, VplSampler};
use vpl_ir::{InstantRadiosity, IrConfig};
use vpl_mir::{MirConfig, MirResampleConfig, MirResampleSampler, MirSampler};
use vpl_rr::{LightPaths, RrConfig, RrSampler, SamplerCandidates};
use vpl_smc::{SmcConfig, SmcSampler};
use vpl_tcas::{TcasConfig, TcasSampler};

/// A parameter error of sampler `name`.
fn param(name: &str) -> impl FnOnce(ParamError) -> SamplingError + '_ {
    move |source| SamplingError::Param { name: name.into(), source }
}

fn boxed<S: VplSampler + 'static>(s: S) -> Box<dyn VplSampler> {
    Box::new(s)
}

fn ir(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls("ir")?;
    let config = IrConfig::from_params(&cx.budget, p).map_err(param("ir"))?;
    InstantRadiosity::new(config).map(boxed).map_err(|e| SamplingError::sampler("ir", e))
}

/// RR's candidate source: key `candidates` names any registered sampler;
/// `ir` (the default, as in the paper) is traced as light paths, so each
/// frame asks for as many candidates as the acceptance rate needs.
fn rr(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls("rr")?;
    cx.needs_indirect("rr")?;
    let config = RrConfig::from_params(&cx.budget, p).map_err(param("rr"))?;
    let source: String = p.get_or("candidates", "ir".to_string()).map_err(param("rr"))?;
    let sampler = if source == "ir" {
        let ir = InstantRadiosity::new(IrConfig::from_params(&cx.budget, p).map_err(param("rr"))?)
            .map_err(|e| SamplingError::sampler("rr", e))?;
        RrSampler::new(config, Box::new(LightPaths(ir)))
    } else if source == "rr" {
        return Err(SamplingError::Param { name: "rr".into(), source: p.out_of_range("candidates", "rr", "another sampler than rr") });
    } else {
        RrSampler::new(config, Box::new(SamplerCandidates(cx.build(&source, p)?)))
    };
    sampler.map(boxed).map_err(|e| SamplingError::sampler("rr", e))
}

fn mir(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls("mir")?;
    cx.needs_indirect("mir")?;
    let config = MirConfig::from_params(&cx.budget, p).map_err(param("mir"))?;
    MirSampler::new(config).map(boxed).map_err(|e| SamplingError::sampler("mir", e))
}

fn mir_resample(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls("mir-resample")?;
    cx.needs_indirect("mir-resample")?;
    let config = MirResampleConfig::from_params(&cx.budget, p).map_err(param("mir-resample"))?;
    MirResampleSampler::new(config).map(boxed).map_err(|e| SamplingError::sampler("mir-resample", e))
}

fn tcas(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls("tcas")?;
    cx.needs_indirect("tcas")?;
    let config = TcasConfig::from_params(&cx.budget, p).map_err(param("tcas"))?;
    TcasSampler::new(config).map(boxed).map_err(|e| SamplingError::sampler("tcas", e))
}

fn smc(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    smc_with(cx, p, "smc", false)
}

/// SMC as the paper has it: the kNN flux (eq. 5 and 7) at the VPLs' own
/// points, unless `flux` or `placement` says otherwise.
fn smc_knn(cx: &SamplerContext, p: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
    smc_with(cx, p, "smc-knn", true)
}

fn smc_with(cx: &SamplerContext, p: &Params, name: &str, paper: bool) -> Result<Box<dyn VplSampler>, SamplingError> {
    cx.needs_vpls(name)?;
    cx.needs_indirect(name)?;
    let config = smc_settings(&cx.budget, p, paper).map_err(param(name))?;
    // A backend that runs these settings wholly on its device does.
    if let Some(twin) = cx.services.samplers.as_ref().and_then(|s| s.twin(name, &cx.budget, p)) {
        return twin.map_err(|source| SamplingError::Sampler { name: name.into(), source });
    }
    SmcSampler::with_services(config, cx.services).map(boxed).map_err(|e| SamplingError::sampler(name, e))
}

/// The toolkit's SMC settings, or the paper's (`paper`: kNN flux at the sites).
fn smc_settings(budget: &Budget, p: &Params, paper: bool) -> Result<SmcConfig, ParamError> {
    if paper { SmcConfig::paper_from_params(budget, p) } else { SmcConfig::from_params(budget, p) }
}

/// The area probes of the SMC entry's settings (`paper`: `smc-knn`'s),
/// where it keeps any ([`SmcConfig::probe_memory`]).
fn smc_memory(paper: bool) -> impl Fn(&Budget, &Params) -> Vec<MemoryPart> + Send + Sync {
    move |budget, p| {
        let Ok(c) = smc_settings(budget, p, paper) else { return Vec::new() };
        match c.probe_memory() {
            0 => Vec::new(),
            bytes => vec![MemoryPart {
                what: format!("SMC area probes: {} VPLs × {} hits × {} iterations", c.vpls, c.resample_ratio, c.probe_iterations),
                bytes,
                keys: &["vpls", "resample-ratio"],
            }],
        }
    }
}

/// The camera samples that `camera-samples` asks of RR, MIR and TCAS: one
/// importon each, cast every frame.
fn camera_memory(_: &Budget, p: &Params) -> Vec<MemoryPart> {
    match p.get_or("camera-samples", 0u64).unwrap_or(0) {
        0 => Vec::new(),
        n => vec![MemoryPart {
            what: format!("camera samples: {n} importons"),
            bytes: n.saturating_mul(std::mem::size_of::<vpl_core::importons::Importon>() as u64),
            keys: &["camera-samples"],
        }],
    }
}

/// The built-in entries, in the order the toolkit lists them.
pub(crate) fn entries() -> Vec<SamplerEntry> {
    let rr_keys = [
        RrConfig::KEYS,
        &[vpl_core::ParamKey {
            key: "candidates",
            default: "ir",
            about: "the candidate source: ir (light paths) or any registered sampler",
        }],
        IrConfig::KEYS,
    ]
    .concat();
    vec![
        SamplerEntry::new("ir", "Instant Radiosity (Keller 1997): VPLs at the diffuse vertices of light paths", ir).with_keys(IrConfig::KEYS),
        SamplerEntry::new(
            "rr",
            "Russian-roulette acceptance (Georgiev & Slusallek 2010): candidates (IR's by default) kept in proportion to the light they bring the camera",
            rr,
        )
        .with_keys(&rr_keys)
        .with_memory(camera_memory),
        SamplerEntry::new(
            "mir",
            "Metropolis Instant Radiosity (Segovia et al. 2007): light paths by Metropolis-Hastings, VPLs of equal power to the camera",
            mir,
        )
        .with_keys(MirConfig::KEYS)
        .with_memory(camera_memory),
        SamplerEntry::new(
            "mir-resample",
            "MIR as the SMC paper ran it: 256·I path-tracer camera paths resampled to I VPLs by the light they bring the camera",
            mir_resample,
        )
        .with_keys(MirResampleConfig::KEYS),
        SamplerEntry::new(
            "tcas",
            "Temporally coherent adaptive sampling (Barák et al. 2013): Metropolis chains over reflective shadow maps, one bounce",
            tcas,
        )
        .with_keys(TcasConfig::KEYS)
        .with_memory(camera_memory),
        SamplerEntry::new(
            "smc",
            "Sequential Monte Carlo Instant Radiosity (Hedman et al. 2017): temporally coherent VPLs on indirectly visible surfaces",
            smc,
        )
        .with_keys(SmcConfig::KEYS)
        .with_memory(smc_memory(false)),
        SamplerEntry::new("smc-knn", "SMC with the paper's flux: radiance over the kNN density of the VPLs (eq. 5 and 7)", smc_knn)
            .with_keys(SmcConfig::KEYS)
            .with_memory(smc_memory(true)),
    ]
}

#[cfg(test)]
mod tests {
    use crate::{Registry, SamplingError};
    use vpl_core::{Budget, Frame, GBuffer, ParamError, Params, SceneSetup, Services, VplSampler};

    fn build(name: &str, budget: Budget, params: &[&str]) -> Result<Box<dyn VplSampler>, SamplingError> {
        Registry::builtin().build(name, budget, &Services::cpu(), &Params::parse(params).unwrap())
    }

    #[test]
    fn names_resolve_or_explain() {
        let b = Budget::default();
        for name in ["ir", "rr", "mir", "mir-resample", "tcas", "smc"] {
            assert_eq!(build(name, b, &[]).unwrap().name(), name);
            assert!(matches!(build(name, Budget::new(0, 5), &[]), Err(SamplingError::Budget(..))), "{name}");
            if name != "ir" {
                assert!(matches!(build(name, Budget::new(2048, 2), &[]), Err(SamplingError::Budget(..))), "{name}");
            }
        }
        assert!(matches!(build("xyz", b, &[]), Err(SamplingError::Unknown(..))));
        let e = build("smc", b, &["resample-ratio=0"]).err().unwrap();
        assert_eq!(e.to_string(), "sampler 'smc': resample-ratio=0: must be from 1 to 16777216");
    }

    #[test]
    fn a_key_the_sampler_does_not_read_is_an_error() {
        let b = Budget::default();
        let e = build("ir", b, &["m-max=4"]).err().unwrap();
        assert!(matches!(&e, SamplingError::Unread { keys, .. } if keys == &["m-max"]), "{e}");
        assert_eq!(e.to_string(), "sampler 'ir' does not read m-max (it reads: path-sampling, fresh-paths)");
        assert!(build("smc", b, &["m-max=4", "warmup=3"]).is_ok());
        assert!(matches!(build("ir", b, &["fresh-paths=maybe"]), Err(SamplingError::Param { source: ParamError::Invalid { .. }, .. })));
        // RR reads IR's keys when IR is its source, and the inner sampler's otherwise.
        assert!(build("rr", b, &["path-sampling=halton"]).is_ok());
        assert!(build("rr", b, &["candidates=smc", "m-max=4"]).is_ok());
        assert!(build("rr", b, &["candidates=tcas", "m-max=4"]).is_err());
        assert!(build("rr", b, &["candidates=rr"]).is_err());
    }

    #[test]
    fn user_samplers_register_and_duplicates_do_not() {
        let mut r = Registry::builtin();
        let entry = crate::SamplerEntry::new("ir-again", "IR under another name", |cx, p| cx.build("ir", p));
        r.register(entry.clone()).unwrap();
        assert!(matches!(r.register(entry), Err(SamplingError::Duplicate(_))));
        assert!(r.names().contains(&"ir-again"));
        let s = r.build("ir-again", Budget::new(64, 5), &Services::cpu(), &Params::parse(["fresh-paths=true"]).unwrap()).unwrap();
        assert_eq!(s.name(), "ir");
    }

    #[test]
    fn rr_around_another_sampler_keeps_the_light() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let camera = setup.camera.with_resolution((32, 32)).unwrap();
        let g = GBuffer::empty();
        let frame = Frame { scene: &setup.scene, camera: &camera, time: 0.0, index: 0, seed: 3, gbuffer: &g, previous: None };
        let mut rr = build("rr", Budget::new(64, 5), &["candidates=smc", "warmup=2"]).unwrap();
        let set = rr.next_frame(&frame);
        assert!(set.stored() > 0 && set.stored() <= 64);
        // The first frame knows no Φ̃_total: every candidate is kept.
        assert_eq!(rr.stats().get("acceptance"), Some(1.0));
    }
}
