//! What a fit of a dataset estimates, and where it searches: the estimated parameters (the
//! default ones, the effects' parameters, or for catalogue pages alone what the pages pin
//! down), each parameter's bounds and start range around the dataset's nominal motor, the
//! motor prior, and, for a page that does not print its displacement, the displacement
//! estimated with the rest. The task layer passes the options in and names them in its
//! errors; the rules live here.

use crate::data::dataset::{Dataset, Kind};
use crate::estimate::fit::displacement::{
    displacement_missing, from_page as displacement_from_page, DisplacementEstimate,
};
use crate::estimate::fit::{most_sensitive_experiment, FitData};
use crate::estimate::problem::prior::Prior;
use crate::estimate::problem::space::{Dimension, ParamSpace, SpaceError};
use crate::estimate::profile::subset::{pinned_subset, PINNED_RELATIVE_SD};
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::{estimated_names, page_prior_extra, MotorParams, ParamId};

/// A search or start range of one parameter, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRange {
    /// The parameter.
    pub name: String,
    /// Lower end, SI.
    pub lo: f64,
    /// Upper end, SI.
    pub hi: f64,
}

/// An item of a range list that is not `name=lo:hi`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not name=lo:hi")]
pub struct RangeSyntax(pub String);

impl ParamRange {
    /// Parses `name=lo:hi,...` (empty items skipped), e.g. `c_in1=1e-9:2e-8,visc=1e-6:1e-3`.
    pub fn parse_list(text: &str) -> Result<Vec<ParamRange>, RangeSyntax> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|item| {
                let bad = || RangeSyntax(item.to_string());
                let (name, range) = item.split_once('=').ok_or_else(bad)?;
                let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
                let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
                let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
                Ok(ParamRange {
                    name: name.trim().to_string(),
                    lo,
                    hi,
                })
            })
            .collect()
    }
}

/// What a fit is asked to estimate and where to search (the search's share of the fit's
/// options).
#[derive(Debug, Clone, Copy)]
pub struct SpaceRequest<'a> {
    /// Parameters to estimate (`None`: the default ones).
    pub estimate: Option<&'a [String]>,
    /// Effects switched on; their parameters are estimated too.
    pub effects: &'a EffectSet,
    /// Search bounds overriding the parameters' own, SI.
    pub bounds: &'a [ParamRange],
    /// Where start points are drawn, SI.
    pub start_ranges: &'a [ParamRange],
    /// Default start range: this factor (> 1) either side of the nominal value.
    pub start_spread: f64,
    /// With the motor prior.
    pub priors: bool,
}

/// Why a fit's search could not be set up. The task layer names the option each concerns.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SetupError {
    /// A bound names a parameter that is not estimated (the bounds' option).
    #[error("'{name}' is not estimated")]
    NotEstimated {
        /// The parameter the bound names.
        name: String,
    },
    /// An estimated parameter's dimension could not be made: an unknown name, bad bounds or
    /// a bad start range (the estimate, bounds and start ranges' options together).
    #[error("{0}")]
    Dimension(SpaceError),
    /// The dimensions do not make a space (a parameter twice, an effect's parameter without
    /// its effect).
    #[error("{0}")]
    Space(SpaceError),
    /// The catalogue pins none of the candidates (the estimate option: name parameters).
    #[error(
        "the catalogue pins none of {} to within {limit_pct:.0} % (1σ)",
        names.join(", ")
    )]
    NothingPinned {
        /// The candidates.
        names: Vec<String>,
        /// The relative 1σ, %, below which a parameter counts as pinned.
        limit_pct: f64,
    },
}

/// The search space of a fit: estimated names (`request.estimate`, else the default set,
/// plus every parameter of the effects switched on), bounds and start ranges, around the
/// dataset's nominal motor `fixed`; `displacement`: a page's displacement estimated from the
/// page, which the fit estimates with the rest and the fixed size-scaled parameters follow.
pub fn search_space(
    fixed: MotorParams,
    request: &SpaceRequest<'_>,
    displacement: Option<&DisplacementEstimate>,
) -> Result<ParamSpace, SetupError> {
    let mut names: Vec<String> = match request.estimate {
        Some(list) => list
            .iter()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
        None => estimated_names(&EffectSet::empty()),
    };
    for e in request.effects.iter() {
        for p in e.parameters() {
            if !names.iter().any(|n| n == p) {
                names.push(p.to_string());
            }
        }
    }
    if let Some(b) = request.bounds.iter().find(|b| !names.contains(&b.name)) {
        return Err(SetupError::NotEstimated {
            name: b.name.clone(),
        });
    }
    let dims = names
        .iter()
        .map(|n| dimension(n, &fixed, request, displacement))
        .collect::<Result<Vec<_>, _>>()
        .map_err(SetupError::Dimension)?;
    let prior = if request.priors {
        Prior::for_motor(&fixed)
    } else {
        Prior::none()
    };
    let v_ref = fixed.v_disp();
    let space = ParamSpace::from_dims(dims, fixed, request.effects.clone())
        .map_err(SetupError::Space)?
        .with_prior(prior);
    // A page without a displacement: what is fixed follows the estimated one (similarity).
    Ok(match displacement {
        Some(_) => space.with_size_following(v_ref),
        None => space,
    })
}

/// One estimated parameter's dimension: the request's bounds, else the page's displacement
/// estimate's or the dead volume's own, else the parameter's search range; its start range
/// from the request, the page's displacement interval, or `start_spread` either side of
/// the nominal value.
fn dimension(
    n: &str,
    fixed: &MotorParams,
    request: &SpaceRequest<'_>,
    displacement: Option<&DisplacementEstimate>,
) -> Result<Dimension, SpaceError> {
    let find = |list: &[ParamRange]| list.iter().find(|r| r.name == n).cloned();
    let id = ParamId::from_name(n);
    let d = match (find(request.bounds), displacement) {
        (Some(r), _) => Dimension::with_bounds(n, r.lo, r.hi)?,
        (None, Some(e)) if id == Some(ParamId::V_DISP) => displacement_dimension(e)?,
        (None, _) if id == Some(ParamId::V_DEAD) && fixed.v_dead() > 0.0 => {
            dead_volume_dimension(fixed.v_dead(), fixed.v_disp() / fixed.z())?
        }
        (None, _) => Dimension::for_param(n, fixed.size())?,
    };
    if id == Some(ParamId::V_DISP) && find(request.start_ranges).is_none() {
        if let Some(e) = displacement {
            return d.with_start_range(e.ci95_m3[0], e.ci95_m3[1]);
        }
    }
    match find(request.start_ranges) {
        Some(r) => d.with_start_range(r.lo, r.hi),
        None => {
            // The rig's nominal value: defaults scaled with the displacement.
            let centre = fixed.get(n).unwrap_or(0.0);
            let spread = request.start_spread;
            if d.log_scale && centre > 0.0 {
                d.clone()
                    .with_start_range(centre / spread, centre * spread)
                    .or(Ok(d))
            } else {
                Ok(d)
            }
        }
    }
}

/// The search dimension of the dead volume (whose default search range starts at 0, no
/// logarithm): 1/10 to 10 times its nominal value `v0`, and below 0.9 of the filling volume
/// `v_fill` (it must stay below it).
fn dead_volume_dimension(v0: f64, v_fill: f64) -> Result<Dimension, SpaceError> {
    let hi = (10.0 * v0).min(0.9 * v_fill);
    Dimension::with_id_bounds(ParamId::V_DEAD, (v0 / 10.0).min(0.5 * hi), hi)
}

/// The search dimension of a displacement estimated from a page: bounds ×/÷ 5 around the
/// page's estimate (wider where its interval is), within the parameter's own domain.
fn displacement_dimension(e: &DisplacementEstimate) -> Result<Dimension, SpaceError> {
    let (domain_lo, domain_hi) = ParamId::V_DISP.spec().search;
    let lo = (e.v_disp_m3 / 5.0).min(e.ci95_m3[0] / 2.0).max(domain_lo);
    let hi = (e.v_disp_m3 * 5.0).max(e.ci95_m3[1] * 2.0).min(domain_hi);
    Dimension::with_id_bounds(ParamId::V_DISP, lo, hi)
}

/// Whether a dataset holds catalogue pages only.
pub fn catalogue_only(ds: &Dataset) -> bool {
    ds.experiments.iter().all(|e| e.kind == Kind::Catalogue)
}

/// Whether a dataset is catalogue pages only whose `[motor]` gives neither a displacement
/// nor a geometry (so the fit estimates the displacement from the pages).
pub fn displacement_unprinted(ds: &Dataset) -> bool {
    catalogue_only(ds) && displacement_missing(&ds.motor)
}

/// For a dataset whose displacement is not printed ([`displacement_unprinted`]): the
/// displacement estimated from the pages (`estimate::fit::displacement`).
pub fn page_displacement(ds: &Dataset, data: &FitData) -> Option<DisplacementEstimate> {
    displacement_unprinted(ds)
        .then(|| displacement_from_page(data, &ds.motor))
        .flatten()
}

/// One parameter of a catalogue's pinning: how well the catalogue pins it, and whether it
/// is estimated.
#[derive(Debug, Clone, PartialEq)]
pub struct Pinning {
    /// The parameter.
    pub name: String,
    /// Relative 1σ at the nominal motor (infinite: unseen).
    pub(crate) relative_sd: f64,
    /// Estimated (pinned to within the limit).
    pub(crate) pinned: bool,
    /// The value it stays fixed at when not pinned, SI.
    pub value: f64,
    /// The kind of experiment that would pin it (when not pinned).
    pub pinned_by: Option<Kind>,
    /// When not pinned and the fit has a prior: the prior's 95 % factor F, on which the
    /// parameter then rests (it is estimated, and its interval is the prior's ×/÷ F).
    pub prior_factor: Option<f64>,
}

/// What catalogue pages alone let a fit estimate: the parameters chosen, and the pinning
/// of every candidate at the nominal motor.
#[derive(Debug, Clone, PartialEq)]
pub struct PageChoice {
    /// The parameters to estimate, in θ order (see [`PageChoice::nothing_pinned`] for pages
    /// that pin none of the candidates).
    pub names: Vec<String>,
    /// The candidates.
    pub candidates: Vec<String>,
    /// Every candidate's pinning.
    pub pinning: Vec<Pinning>,
    /// The relative 1σ, %, below which a parameter counts as pinned.
    pub limit_pct: f64,
}

impl PageChoice {
    /// The error of pages that pin none of the candidates: without a prior the fit would
    /// estimate nothing; with one it would be the prior alone, every figure it predicts the
    /// default motor's, and nothing the page prints would move it.
    pub fn nothing_pinned(&self) -> Option<SetupError> {
        let pinned = self.pinning.iter().any(|p| p.pinned);
        (!pinned).then(|| SetupError::NothingPinned {
            names: self.candidates.clone(),
            limit_pct: self.limit_pct,
        })
    }
}

/// For a dataset of catalogue pages only: the parameters the catalogue pins down at the
/// nominal motor `nominal` (`estimate::profile::subset`) and, with the motor prior, those
/// it leaves open too (they rest on their priors); with `displacement_estimated`, the
/// displacement as well.
pub fn page_estimates(
    data: &FitData,
    nominal: MotorParams,
    priors: bool,
    displacement_estimated: bool,
) -> Result<PageChoice, SetupError> {
    let motor = Motor::new(nominal, EffectSet::empty());
    let prior = if priors {
        Prior::for_motor(motor.params())
    } else {
        Prior::none()
    };
    let mut names = estimated_names(&EffectSet::empty());
    if !prior.is_empty() {
        // With the motor prior, the two parameters that shape how torque and flow change with
        // the supply pressure are estimated too, resting on their priors where the page is
        // silent: held at their defaults, a page's torque deficit went into the Coulomb
        // friction, a constant that eats a growing share of the torque at lower pressures
        // (docs/estimation.md, "What a page cannot pin").
        names.extend(
            page_prior_extra()
                .into_iter()
                .filter(|id| prior.term(*id).is_some())
                .map(|id| id.name().to_string()),
        );
    }
    let limit_pct = 100.0 * PINNED_RELATIVE_SD;
    let Some(verdicts) = pinned_subset(data, &motor, &names) else {
        return Err(SetupError::NothingPinned { names, limit_pct });
    };
    let pinning: Vec<Pinning> = verdicts
        .iter()
        .map(|p| Pinning {
            name: p.name.clone(),
            relative_sd: p.relative_sd,
            pinned: p.pinned,
            value: motor.params().get(&p.name).unwrap_or(f64::NAN),
            pinned_by: most_sensitive_experiment(&motor, &p.name),
            prior_factor: (!p.pinned)
                .then(|| {
                    ParamId::from_name(&p.name)
                        .and_then(|id| prior.term(id))
                        .map(|t| t.factor95())
                })
                .flatten(),
        })
        .collect();
    // With a prior every parameter is estimated: what the pages leave open rests on its
    // prior, and the covariance (and so predict's bands) carries it.
    let mut chosen: Vec<String> = pinning
        .iter()
        .filter(|p| p.pinned || p.prior_factor.is_some())
        .map(|p| p.name.clone())
        .collect();
    if displacement_estimated && !chosen.is_empty() {
        // Not printed: the displacement is estimated with the rest, from the page.
        chosen.push(ParamId::V_DISP.name().to_string());
    }
    Ok(PageChoice {
        names: chosen,
        candidates: names,
        pinning,
        limit_pct,
    })
}
