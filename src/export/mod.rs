//! Fits in the formats of other tools: the PEtab v1 tables (`petab`), so that a fit's
//! likelihood can be read, linted and re-evaluated by the parameter-estimation community's
//! tools (petab, pyPESTO) without vanefit's own file formats.
//! And the fitted motor as an FMU (`fmu`), which system simulators run.

pub mod fmu;
pub mod petab;
