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
    # Its page holds the parameter table with the fitted values.
    page = exact._repr_html_()
    assert page.startswith("<iframe srcdoc=") and "identify stribeck" in page
    assert f"{exact['f_c']['value']:.4g}" in page


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


def test_record_fit_recovers_the_rigid_stage_from_arrays_and_files(root, tmp_path):
    """A lab-style record of the rigid one-bearing stage (the full assembled
    model) gives its six LuGre parameters and its mass back through the
    one-mass output-error fit, from arrays and from a CSV file; the progress
    callback sees every iteration."""
    t, force, position, truth = fistage.identify.simulate_record(root / "robots/stage_1dof_rigid.urdf")
    assert t.size == 70000 and numpy.all(numpy.diff(t) > 0)
    seen = []
    fit = fistage.identify.record(t, force, position, progress=lambda i, rms: seen.append((i, rms)))
    for name in ("f_c", "f_s", "v_s", "sigma0", "sigma1", "sigma2", "mass"):
        assert fit[name]["value"] == pytest.approx(truth[name], rel=1e-3), name
        low, high = fit[name]["ci95"]
        assert low < high
    assert fit.simulated.shape == t.shape
    assert len(seen) >= 2 and seen[-1][1] < 1e-9
    # The fit's page, as `fistage identify record` writes it: in Jupyter and on file.
    assert fit._repr_html_().startswith("<iframe srcdoc=")
    fit.write_page(tmp_path / "fit.html")
    assert "record and fit" in (tmp_path / "fit.html").read_text()
    csv = tmp_path / "run.csv"
    numpy.savetxt(csv, numpy.column_stack([t, force, position * 1e9]), delimiter=",",
                  header="t_s,f_servo_N,x_nm", comments="", fmt="%.17g")
    t2, force2, position2 = fistage.identify.read_record(csv)
    assert numpy.allclose(position2, position, rtol=0, atol=1e-15)
    known = fistage.identify.record(t2, force2, position2, mass=truth["mass"])
    assert known["mass"]["std_error"] == 0.0
    assert known["f_c"]["value"] == pytest.approx(truth["f_c"], rel=1e-3)


def test_closed_loop_record_is_fitted_inside_the_scenario_servo(root):
    """A run of the shipped sine-tracking scenario's servo gives the stage's
    parameters back when the fit closes the same servo around its plant;
    a stage with FI is refused by name."""
    scenario = root / "scenarios/identify/closed_loop_sine.toml"
    t, force, position, truth = fistage.identify.simulate_record(scenario, closed_loop=True, duration=2.0)
    assert t.size == 20001
    fit = fistage.identify.record(t, force, position, mass=truth["mass"], horizon=None,
                                  closed_loop=scenario)
    assert "closed_loop_sine" in fit.report["closed_loop"]
    for name in ("f_c", "f_s", "v_s", "sigma0", "sigma1", "sigma2"):
        assert fit[name]["value"] == pytest.approx(truth[name], rel=1e-3), name
    with pytest.raises(fistage.LoadError, match="fig05a_fi.toml.*isolator"):
        fistage.identify.record(t, force, position, closed_loop=root / "scenarios/paper/fig05a_fi.toml")


def test_record_fit_stops_when_the_callback_raises(root, tmp_path):
    t, force, position, _ = fistage.identify.simulate_record(root / "robots/stage_1dof_rigid.urdf")

    def stop(iteration, rms):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        fistage.identify.record(t, force, position, progress=stop)
    with pytest.raises(fistage.Error, match="does not increase"):
        fistage.identify.record(t[::-1], force, position)
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,force_N,y_nm\n0,0,0\n")
    with pytest.raises(fistage.Error, match="bad.csv.*no position column"):
        fistage.identify.read_record(bad)


def test_a_stage_fit_takes_a_scenario_paths_and_several_records(root):
    """The FI stage's isolator stiffness and bearing friction from two 2 kHz
    records at once, from a scenario 10% off: the values come back, the
    covariance names each parameter's path, and the simulated readings are
    there per record."""
    robot = (root / "robots/stage_1dof_fi.urdf").as_posix()
    truth = fistage.Scenario.from_toml(f'robot = "{robot}"\nduration = 1.0\n')
    start = truth.with_overrides({"overrides.isolator.k_x": 4.4e4,
                                  "overrides.bearing_friction.f_c": 4.6,
                                  "overrides.bearing_friction.sigma0": 2.0e6})
    records = []
    for seed in (1, 2):
        t, force, position, _ = fistage.identify.simulate_record(robot, seed=seed, rate=2000.0)
        records.append({"t": t, "force": force, "position": position})
    paths = ["overrides.isolator.k_x", "overrides.bearing_friction.f_c",
             "overrides.bearing_friction.sigma0"]
    fit = fistage.identify.record(scenario=start, paths=paths, records=records)
    for path, value in zip(paths, (4e4, 5.1, 2.2e6)):
        assert fit[path]["value"] == pytest.approx(value, rel=1e-3), path
    assert fit.undetermined == []
    assert fit.report["covariance"]["paths"] == paths
    assert len(fit.simulated) == 2 and fit.simulated[1][0].shape == records[1]["t"].shape
    with pytest.raises(fistage.Error, match="nothing"):
        fistage.identify.record(scenario=start, paths=["overrides.nothing.k_x"], records=records)
