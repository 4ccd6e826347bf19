"""vanefit's ensemble sampler against emcee, and its diagnostics against arviz, on the same
log-posterior: the likelihood of a fit of the catalogue dataset (one supply pressure; a
curved valley between c_out2 and c_ext that the delta method cannot follow), and the
posterior of the default page fit with its motor prior (ten parameters, most resting on
their prior), as `vanefit predict --bands samples` samples it.

Both samplers start from the same walkers; their means and 2.5/50/97.5 % quantiles must
agree within the Monte-Carlo error the effective sample sizes give. vanefit's R̂ and ESS
must equal arviz's on the same chains (vanefit's and emcee's) to rounding."""

import json

import numpy as np
import pytest

import vanefit
from conftest import ROOT, run_cli  # noqa: F401

CATALOGUE = ROOT / "measurements" / "ar034-synthetic-catalogue"
WALKERS, STEPS, BURN = 16, 3000, 1000


@pytest.fixture(scope="module")
def posterior(tmp_path_factory):
    out = tmp_path_factory.mktemp("catalogue") / "fit.json"
    # Without the motor prior: the likelihood alone, on the four parameters the page pins (or
    # half-pins: the c_out2/c_ext valley), which is what both samplers are compared on.
    run_cli("fit", CATALOGUE, "--priors", "none", "--no-plots", "--out", out)
    assert len(json.loads(out.read_text())["statistics"]) > 0
    ds = vanefit.load_dataset(CATALOGUE)
    return vanefit.likelihood(ds, out)


@pytest.fixture(scope="module")
def starts(posterior):
    rng = np.random.default_rng(3)
    centre = posterior.to_coords(posterior.x_hat)
    x0 = centre + 0.01 * rng.standard_normal((WALKERS, len(centre)))
    assert all(np.isfinite(posterior.log_posterior(x)) for x in x0)
    return x0


@pytest.fixture(scope="module")
def runs(posterior, starts):
    emcee = pytest.importorskip("emcee")
    mine = posterior.sample(starts, STEPS, burn_in=BURN, seed=7)["chain"]
    sampler = emcee.EnsembleSampler(
        WALKERS, starts.shape[1], posterior.log_posterior,
        moves=emcee.moves.StretchMove(a=2.0),
    )
    sampler.random_state = np.random.RandomState(11).get_state()
    sampler.run_mcmc(starts, BURN + STEPS, progress=False)
    theirs = sampler.get_chain(discard=BURN)
    return mine, theirs


def _by_chain(chain):
    """steps × walkers × parameters → walkers × steps × parameters."""
    return np.transpose(chain, (1, 0, 2))


def test_the_log_posterior_is_zero_at_the_estimate_and_minus_inf_outside_the_bounds(posterior):
    x = posterior.to_coords(posterior.x_hat)
    assert abs(posterior.log_posterior(x)) < 1e-6 * max(1.0, posterior.chi2_min)
    outside = x.copy()
    outside[0] = np.log(posterior.upper[0]) + 1.0
    assert posterior.log_posterior(outside) == -np.inf
    np.testing.assert_allclose(posterior.to_values(x), posterior.x_hat, rtol=1e-12)


def test_vanefit_s_sampler_agrees_with_emcee_within_monte_carlo_error(runs):
    _agree_within_monte_carlo_error(*runs)


def _agree_within_monte_carlo_error(mine, theirs, diagnostics=None):
    """Means and 2.5/50/97.5 % quantiles of two runs (steps × walkers × parameters) agree
    within 4 Monte-Carlo standard errors (from the runs' effective sample sizes).
    `diagnostics`: the runs' `chain_diagnostics` where the caller has them already (on the
    page's 48 × 6000 draws each takes seconds)."""
    if diagnostics is None:
        diagnostics = [vanefit.chain_diagnostics(_by_chain(run)) for run in (mine, theirs)]
    d_mine, d_theirs = diagnostics
    flat_m = mine.reshape(-1, mine.shape[2])
    flat_t = theirs.reshape(-1, theirs.shape[2])
    lines = []
    for j in range(flat_m.shape[1]):
        sd = 0.5 * (flat_m[:, j].std() + flat_t[:, j].std())
        ess_b = np.array([d_mine["ess_bulk"][j], d_theirs["ess_bulk"][j]])
        ess_t = np.array([d_mine["ess_tail"][j], d_theirs["ess_tail"][j]])
        se_mean = sd * np.sqrt(np.sum(1.0 / ess_b))
        diff = flat_m[:, j].mean() - flat_t[:, j].mean()
        lines.append(f"param {j}: mean {flat_m[:, j].mean():.4f} vs {flat_t[:, j].mean():.4f} "
                     f"(± {se_mean:.4f})")
        assert abs(diff) < 4 * se_mean, lines[-1]
        for q, ess in ((0.025, ess_t), (0.5, ess_b), (0.975, ess_t)):
            qm, qt = np.quantile(flat_m[:, j], q), np.quantile(flat_t[:, j], q)
            # Standard error of a quantile from the ESS: the spread of the q ± se_p
            # quantiles of the pooled draws, se_p = √(q(1 − q)/ESS).
            pooled = np.concatenate([flat_m[:, j], flat_t[:, j]])
            se = sum(
                (np.quantile(pooled, min(q + np.sqrt(q * (1 - q) / e), 1.0))
                 - np.quantile(pooled, max(q - np.sqrt(q * (1 - q) / e), 0.0))) / 2
                for e in ess
            ) / np.sqrt(2)
            lines.append(f"param {j}: q{q} {qm:.4f} vs {qt:.4f} (± {se:.4f})")
            assert abs(qm - qt) < 4 * se + 1e-12, lines[-1]
    print("\n".join(lines))


PAGE_WALKERS, PAGE_STEPS, PAGE_BURN = 48, 6000, 3000


@pytest.fixture(scope="module")
def page_runs(page_fit):
    """vanefit's sampler and emcee on the page fit's posterior with its motor prior, from
    the same walkers around the estimate."""
    emcee = pytest.importorskip("emcee")
    post = vanefit.likelihood(vanefit.load_dataset(ROOT / "measurements" / "ar034-synthetic-catalogue"), page_fit)
    assert post.priors and len(post.prior_terms) == len(post.names)
    rng = np.random.default_rng(5)
    centre = post.to_coords(post.x_hat)
    # Spread at 0.3 prior σ (in ln v; in v for a linear-scale parameter): the ensemble then
    # needs no long expansion from a point to the prior's width.
    sd = np.array([t["sd_ln"] for t in post.prior_terms])
    sd = sd * np.where(post.log_scale, 1.0, post.x_hat)
    lo, hi = post.to_coords(post.lower), post.to_coords(post.upper)
    x0 = np.clip(centre + 0.3 * sd * rng.standard_normal((PAGE_WALKERS, len(centre))),
                 lo + 1e-9, hi - 1e-9)
    mine = post.sample(x0, PAGE_STEPS, burn_in=PAGE_BURN, seed=9)["chain"]
    sampler = emcee.EnsembleSampler(
        PAGE_WALKERS, x0.shape[1], post.log_posterior, moves=emcee.moves.StretchMove(a=2.0)
    )
    sampler.random_state = np.random.RandomState(13).get_state()
    sampler.run_mcmc(x0, PAGE_BURN + PAGE_STEPS, progress=False)
    return post, mine, sampler.get_chain(discard=PAGE_BURN)


def test_the_page_posterior_holds_the_motor_prior(page_fit):
    """At the estimate ln p = 0 with or without the prior; one prior σ from a prior
    parameter's median in ln v costs ½ more with it (the likelihood part unchanged)."""
    ds = vanefit.load_dataset(ROOT / "measurements" / "ar034-synthetic-catalogue")
    with_prior = vanefit.likelihood(ds, page_fit)
    alone = vanefit.likelihood(ds, page_fit, priors=False)
    doc = json.loads(page_fit.read_text())
    st = doc["statistics"]
    assert with_prior.chi2_min == pytest.approx(st["likelihood_chi2"] + st["prior_chi2"], rel=1e-12)
    assert with_prior.chi2(with_prior.x_hat) == pytest.approx(with_prior.chi2_min, rel=1e-9)
    assert alone.chi2(alone.x_hat) == pytest.approx(st["likelihood_chi2"], rel=1e-9)
    x = with_prior.to_coords(with_prior.x_hat)
    assert abs(with_prior.log_posterior(x)) < 1e-9 and abs(alone.log_posterior(x)) < 1e-9
    terms = {t["parameter"]: t for t in with_prior.prior_terms}
    j = with_prior.names.index("visc")
    y = x.copy()
    y[j] = np.log(terms["visc"]["median"]) + terms["visc"]["sd_ln"]
    z_hat = (x[j] - np.log(terms["visc"]["median"])) / terms["visc"]["sd_ln"]
    extra = with_prior.log_posterior(y) - alone.log_posterior(y)
    assert extra == pytest.approx(-0.5 * (1.0 - z_hat**2), abs=1e-9)
    # The residual vector carries one row per prior term, its squares the objective.
    r = with_prior.residuals(with_prior.x_hat)
    assert len(r) == len(alone.residuals(alone.x_hat)) + len(terms)
    assert float(np.sum(r**2)) == pytest.approx(with_prior.chi2_min, rel=1e-9)


def test_vanefit_s_sampler_agrees_with_emcee_on_a_page_with_its_prior(page_runs):
    post, mine, theirs = page_runs
    # Walkers of an ensemble are far from independent chains (R̂ over walkers stays above
    # 1.2 here); what the comparison needs is enough effective draws for its errors.
    diagnostics = [vanefit.chain_diagnostics(_by_chain(run)) for run in (mine, theirs)]
    for d in diagnostics:
        assert np.all(d["ess_bulk"] > 40) and np.all(d["ess_tail"] > 40), d
    _agree_within_monte_carlo_error(mine, theirs, diagnostics)
    # What the page cannot pin follows its prior: a leak's 95 % interval spans a good part
    # of the prior's (F = 4 either way), far wider than the catalogue pins c_in1.
    flat = mine.reshape(-1, mine.shape[2])
    width = lambda n: np.subtract(*np.quantile(flat[:, post.names.index(n)], [0.975, 0.025]))
    terms = {t["parameter"]: t for t in post.prior_terms}
    assert width("c_12") > 0.5 * 2 * 1.96 * terms["c_12"]["sd_ln"]
    assert width("c_in1") < 0.5 * width("c_12")


@pytest.mark.parametrize("which", [0, 1], ids=["vanefit chains", "emcee chains"])
def test_diagnostics_equal_arviz_s_on_the_same_chains(runs, which):
    az = pytest.importorskip("arviz")
    chains = _by_chain(runs[which])
    mine = vanefit.chain_diagnostics(chains)
    for j in range(chains.shape[2]):
        x = chains[:, :, j]
        assert mine["rhat"][j] == pytest.approx(float(az.rhat(x, method="rank")), rel=1e-6)
        assert mine["ess_bulk"][j] == pytest.approx(float(az.ess(x, method="bulk")), rel=1e-6)
        assert mine["ess_tail"][j] == pytest.approx(float(az.ess(x, method="tail")), rel=1e-6)


def test_the_sampler_is_deterministic_for_a_seed(posterior, starts):
    a = posterior.sample(starts, 20, seed=3)
    b = posterior.sample(starts, 20, seed=3)
    c = posterior.sample(starts, 20, seed=4)
    np.testing.assert_array_equal(a["chain"], b["chain"])
    assert not np.array_equal(a["chain"], c["chain"])
    assert a["chain"].shape == (20, WALKERS, starts.shape[1])
