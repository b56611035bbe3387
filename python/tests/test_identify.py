"""fistage.identify on arrays: the fits recover known parameters from
curves made with the model's own laws (paper Eq. 30 and Eq. 33), their
intervals hold the truth under noise, and bad input raises fistage.Error."""

import numpy
import pytest

import fistage

TRUTH = dict(sigma0=2.2e6, sigma1=237.0, sigma2=14.2, f_c=5.1, f_s=6.5, v_s=0.0167)


def steady_friction(v):
    level = TRUTH["f_c"] + (TRUTH["f_s"] - TRUTH["f_c"]) * numpy.exp(-(v / TRUTH["v_s"]) ** 2)
    return level * numpy.sign(v) + TRUTH["sigma2"] * v


def test_stribeck_recovers_table1_and_its_intervals_hold():
    v = numpy.concatenate([-numpy.geomspace(2e-4, 0.2, 30), numpy.geomspace(2e-4, 0.2, 30)])
    exact = fistage.identify.stribeck(v, steady_friction(v))
    for name in ("f_c", "f_s", "v_s", "sigma2"):
        assert exact[name]["value"] == pytest.approx(TRUTH[name], rel=1e-5), name
    assert exact["v_s"]["unit"] == "m/s"
    rng = numpy.random.default_rng(7)
    noisy = fistage.identify.stribeck(v, steady_friction(v) + 0.02 * rng.standard_normal(v.size))
    for name in ("f_c", "f_s", "v_s", "sigma2"):
        low, high = noisy[name]["ci95"]
        assert low <= TRUTH[name] <= high, (name, noisy[name])
        assert noisy[name]["std_error"] > 0
    robust = fistage.identify.stribeck(v, steady_friction(v), loss="huber", asymmetric=True)
    assert robust["f_c"]["value"] == pytest.approx(TRUTH["f_c"], rel=1e-3)


def test_frf_recovers_the_premotion_stiffness_and_mass():
    freq = numpy.geomspace(10.0, 1000.0, 40)
    s = 2j * numpy.pi * freq
    mass = 1.5
    damping = TRUTH["sigma1"] + TRUTH["sigma2"]
    response = 1.0 / (mass * s**2 + damping * s + TRUTH["sigma0"])
    fit = fistage.identify.frf(freq, response=response)
    assert fit["sigma0"]["value"] == pytest.approx(TRUTH["sigma0"], rel=1e-6)
    assert fit["sigma1_plus_sigma2"]["value"] == pytest.approx(damping, rel=1e-6)
    assert fit["mass"]["value"] == pytest.approx(mass, rel=1e-6)
    split = fistage.identify.frf(freq, magnitude=numpy.abs(response), phase=numpy.angle(response),
                                 mass=mass, sigma2=TRUTH["sigma2"])
    assert split["sigma1"]["value"] == pytest.approx(TRUTH["sigma1"], rel=1e-5)


def test_bad_input_raises_fistage_errors():
    with pytest.raises(fistage.Error, match="loss"):
        fistage.identify.stribeck([0.01, 0.02], [5.0, 5.1], loss="l3")
    with pytest.raises(fistage.Error, match="one force per velocity"):
        fistage.identify.stribeck([0.01, 0.02, 0.03], [5.0, 5.1])
    with pytest.raises(fistage.Error):
        fistage.identify.stribeck([0.01, 0.02], [5.0, 5.1])
    with pytest.raises(fistage.Error, match="response"):
        fistage.identify.frf([10.0, 20.0])
    with pytest.raises(KeyError, match="sigma0"):
        fistage.identify.frf(numpy.geomspace(10, 1000, 20),
                             response=1 / (1.5 * (2j * numpy.pi * numpy.geomspace(10, 1000, 20)) ** 2 + 2.2e6))["mu"]
