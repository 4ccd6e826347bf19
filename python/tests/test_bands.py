"""``vanefit.predict(fit, data=…, bands=…)``: the dataset found from the fit file as the
command line finds it, ``auto`` falling back to the delta method with the reason, and the
posterior samples as an ``arviz.InferenceData`` whose diagnostics are vanefit's."""

import json

import numpy as np
import pytest

import vanefit

from conftest import CATALOGUE, run_cli

SHORT = dict(steps=200, burn_in=100, draws=60, seed=3)


def test_predict_samples_the_dataset_the_fit_file_records_or_the_one_given(page_fit):
    p = vanefit.predict(page_fit, pressures=[4, 6.3], bands="samples", **SHORT)
    assert p.method == "samples"
    assert p.bands["dataset"]["found"] is True
    assert "the fit file's dataset_path" in p.bands["dataset"]["where"]
    assert p.bands["reason"].startswith("bands from 60 posterior samples (R̂ ≤")
    # The same samples from the dataset given, as a Dataset or as its folder.
    for data in (vanefit.load_dataset(CATALOGUE), CATALOGUE):
        q = vanefit.predict(page_fit, pressures=[4, 6.3], bands="samples", data=data, **SHORT)
        np.testing.assert_array_equal(p.samples["chain"], q.samples["chain"])
        assert q.csv("catalogue") == p.csv("catalogue")
    # The same tables as the command line's with the same options.
    with pytest.raises(vanefit.ParameterError, match="bands"):
        vanefit.predict(page_fit, bands="bootstrap")


def test_auto_falls_back_to_delta_with_the_reason_and_keeps_the_summary(page_fit, tmp_path):
    p = vanefit.predict(page_fit, pressures=[4], steps=20, burn_in=10, draws=40)
    assert p.method == "delta" and p.bands["asked"] == "auto"
    assert p.posterior is not None and p.posterior["converged"] is False
    assert p.bands["reason"].startswith(
        "delta-method bands: the samples did not converge (largest R̂ "
        f"{p.posterior['rhat_max']:.3f}"
    )
    assert p.samples is not None  # drawn, though not used
    # delta: instant, nothing sampled.
    d = vanefit.predict(page_fit, pressures=[4], bands="delta")
    assert d.method == "delta" and d.posterior is None and d.samples is None
    with pytest.raises(ValueError, match="bands"):
        d.to_arviz()
    # A fit whose dataset cannot be found: delta bands, saying where it looked.
    doc = json.loads(page_fit.read_text())
    doc["dataset_path"] = "../nowhere/ar034-synthetic-catalogue"
    moved = tmp_path / "moved.json"
    moved.write_text(json.dumps(doc))
    m = vanefit.predict(moved, pressures=[4])
    assert m.method == "delta" and m.bands["dataset"]["found"] is False
    assert "was not found (looked at" in m.bands["reason"]
    with pytest.raises(vanefit.ParameterError, match="not found"):
        vanefit.predict(moved, pressures=[4], bands="samples")


def test_to_arviz_round_trips_vanefit_s_samples_and_diagnostics(page_fit):
    az = pytest.importorskip("arviz")
    stages = []
    p = vanefit.predict(page_fit, pressures=[5], bands="samples",
                        progress=lambda *a: stages.append(a), **SHORT)
    # A transport sampler runs a pilot ensemble first; every sampler samples, then propagates.
    sampler = p.posterior["sampler"]
    pilot = {"pilot"} if sampler == "transport_chains" else set()
    assert {s[0] for s in stages} == {"sampling", "propagating"} | pilot
    idata = p.to_arviz()
    assert idata.attrs["sampler"] == f"vanefit {sampler}"
    post = idata.posterior
    names = list(p.posterior["parameters"])
    assert list(post.data_vars) == names
    walkers, steps = p.posterior["walkers"], p.posterior["steps"]
    assert post.sizes["chain"] == walkers and post.sizes["draw"] == steps
    assert set(idata.sample_stats.data_vars) >= {"lp", "acceptance_rate"}
    # SI values: the chain's, each walker a chain.
    chain = p.samples["chain"]
    for i, n in enumerate(names):
        np.testing.assert_array_equal(post[n].values, chain[:, :, i].T)
    np.testing.assert_allclose(
        idata.sample_stats["acceptance_rate"].values.mean(), p.posterior["acceptance"]
    )
    # vanefit's summary is arviz's on the same chains, in the sampler's coordinates (ln θ
    # of a log-scale parameter): arviz's rank R̂ folds the draws about their median, which a
    # logarithm moves, and its tail ESS takes the 5 and 95 % quantiles by interpolation
    # between draws, which a logarithm moves too.
    lik = vanefit.likelihood(vanefit.load_dataset(CATALOGUE), page_fit)
    log_scale = dict(zip(lik.names, lik.log_scale))
    for n in names:
        mine = p.posterior["parameters"][n]
        x = post[n].values
        x = np.log(x) if log_scale[n] else x
        assert mine["rhat"] == pytest.approx(float(az.rhat(x, method="rank")), rel=1e-6)
        assert mine["ess_bulk"] == pytest.approx(float(az.ess(x, method="bulk")), rel=1e-6)
        assert mine["ess_tail"] == pytest.approx(float(az.ess(x, method="tail")), rel=1e-6)


def test_likelihood_samples_convert_to_arviz(page_fit):
    az = pytest.importorskip("arviz")
    lik = vanefit.likelihood(vanefit.load_dataset(CATALOGUE), page_fit)
    x0 = lik.to_coords(lik.x_hat)
    rng = np.random.default_rng(1)
    starts = x0 + 1e-3 * rng.standard_normal((2 * len(x0) + 2, len(x0)))
    s = lik.sample(starts, 30, seed=2)
    idata = s.to_arviz()
    assert list(idata.posterior.data_vars) == lik.names
    assert idata.attrs["units"] == "coords"
    d = vanefit.chain_diagnostics(np.transpose(s["chain"], (1, 0, 2)))
    rhat = az.rhat(idata, method="rank")
    for j, n in enumerate(lik.names):
        assert d["rhat"][j] == pytest.approx(float(rhat[n]), rel=1e-6)
