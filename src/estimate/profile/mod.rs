//! How certain an estimate is: profile-likelihood and curvature intervals
//! (`uncertainty`), and which parameters a dataset can pin down at all (`subset`).

pub(crate) mod subset;
pub(crate) mod uncertainty;
