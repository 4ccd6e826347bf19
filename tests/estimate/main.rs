//! Estimation: the `fit` command end to end ([`cli_fit`]), the multi-start runner
//! ([`multistart`]), parameter recovery ([`recovery`]) and interval coverage on independent
//! data ([`coverage`]), the likelihood rebuilt from a fit file ([`fit_likelihood`]) and its
//! PEtab export ([`export_petab`]).

mod cli_fit;
#[path = "../common/mod.rs"]
mod common;
mod coverage;
mod every_size;
mod export_fmu;
mod export_petab;
mod fit_likelihood;
mod multistart;
mod page_subsets;
mod recovery;
mod sampler;
extern crate twin;
