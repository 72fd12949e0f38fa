"""granagg.meanfield against exact solutions and closed forms."""
import math

import numpy as np
import pytest

from granagg import meanfield


def test_constant_kernel_equals_the_exact_solution():
    # K = K0 = 1 from n_1(0) = 1, a = t/2: n_k = (1+a)^-2 (a/(1+a))^(k-1), M0 = 1/(1+a),
    # S = M2/M1 = 1 + t (tests/meanfield/test_discrete_solver.cpp)
    c = meanfield.smoluchowski(kernel="constant", method="discrete", t_end=50.0, M=4096,
                               n_s_max=40)
    assert c.valid.all() and not c.valid.flags.writeable
    assert np.allclose(c.S, 1 + c.t, rtol=1e-6)
    a = c.t / 2
    assert np.allclose(c.M0, 1 / (1 + a), rtol=1e-6)
    k = c.sizes
    assert list(k[:3]) == [1, 2, 3]
    exact = (1 + a[:, None]) ** -2 * (a[:, None] / (1 + a[:, None])) ** (k[None, :] - 1)
    assert np.allclose(c.N_s, exact, rtol=1e-5, atol=1e-12)
    # S = 1 + t has the local slope ln[(1+t)/(1+t/p)] / ln p; S(t/p) is interpolated linearly
    # in (ln t, ln S) between samples D = ln(10)/20 apart, which errs by at most
    # D^2/8 max|d^2 ln S / d(ln t)^2| = D^2/8 * 1/4 in ln S: 6e-4 in z after the division by ln 2
    ok = np.isfinite(c.local_slope)
    p = 2.0
    D = math.log(10) / 20
    assert np.allclose(c.local_slope[ok],
                       np.log((1 + c.t[ok]) / (1 + c.t[ok] / p)) / math.log(p),
                       rtol=0, atol=D ** 2 / 8 / 4 / math.log(2))


def test_sectional_beta_kernel_reaches_its_scaling_exponent():
    # beta = 3: z = 3 beta / (beta + 3) = 1.5 at late times (the mean field's exponent)
    c = meanfield.smoluchowski(beta=3.0, t_end=1e6)
    late = np.isfinite(c.local_slope) & (c.t > 1e5)
    assert abs(np.median(c.local_slope[late]) - 1.5) < 0.02
    assert c.N_s is None and c.stopped == ""


def test_smoluchowski_errors_name_the_option():
    with pytest.raises(ValueError, match="--t-end"):
        meanfield.smoluchowski(t_end=-1.0)
    with pytest.raises(ValueError, match="--method"):
        meanfield.smoluchowski(method="spectral")
    with pytest.raises(TypeError):
        meanfield.smoluchowski(betta=2.0)


def test_kinetic_haff_equals_the_closed_form():
    df = meanfield.kinetic("haff", eps=0.9, phi=0.076, points=20)
    tau0 = float(df.attrs["tau0"])
    assert np.allclose(df["T"], 1 / (1 + df["t"] / tau0) ** 2, rtol=1e-12)
    assert list(df.columns) == ["t", "T", "slope"]
    assert df.attrs["eps"] == "0.9"


def test_kinetic_cooling_and_enskog():
    cool = meanfield.kinetic("cooling", points=30, t_end=100.0)
    assert (np.diff(cool["T"]) < 0).all() and cool["T"].iloc[0] == 1.0
    en = meanfield.kinetic("enskog", phi=0.076)
    g2 = (1 - 0.076 / 2) / (1 - 0.076) ** 3  # Carnahan-Starling
    assert en["g2"].iloc[0] == pytest.approx(g2, rel=1e-12)
    with pytest.raises(TypeError, match="known"):
        meanfield.kinetic("haff", epsilon=0.9)
    with pytest.raises(ValueError, match="--phi"):
        meanfield.kinetic("enskog", phi=0.9)
    with pytest.raises(ValueError, match="kind"):
        meanfield.kinetic("fluid")


def test_fit_beta_recovers_the_beta_of_a_mean_field_curve():
    # S(t) of the mean field itself with beta = 3, over the late decades where its local slope
    # has settled: beta from z is 3 within 0.1
    c = meanfield.smoluchowski(beta=3.0, t_end=1e5, t_min=1.0)
    fit = meanfield.fit_beta(c.t, c.S, window=(1e3, 1e5), curve_fit=False)
    assert fit.z == pytest.approx(1.5, abs=0.03)
    assert fit.beta == pytest.approx(3.0, abs=0.1)
    assert any("beta" in line for line in fit.report)
    with pytest.raises(ValueError):
        meanfield.fit_beta([1, 2], [1, 2])
