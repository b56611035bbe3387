"""The Python face of fistage against what the library and the paper say:
the Fig. 5b limit cycle, parameter overrides that leave the original alone
and are checked by their rules, errors that name the key, pickling for
parallel runs that give the same numbers, and the result's arrays."""

import concurrent.futures
import pickle

import numpy
import pytest

import fistage


def fig05b(root):
    return fistage.load(root / "scenarios/paper/fig05b_fi.toml")


def test_fig05b_limit_cycle_matches_the_program(root):
    result = fig05b(root).run()
    x = result["encoder.position"]
    assert isinstance(x, numpy.ndarray) and x.dtype == numpy.float64
    assert x.shape == result.time.shape == (5001,)
    window = result.time >= 2.5
    peak_to_peak = x[window].max() - x[window].min()
    # RESULTS.md: 69 um peak-to-peak (paper Fig. 5b: the FI stage keeps oscillating).
    assert 68e-6 < peak_to_peak < 70.5e-6, peak_to_peak
    stats = result.summary["signals"]["encoder.position"]
    assert stats["peak_to_peak"] == pytest.approx(peak_to_peak, rel=1e-12)
    assert result.units["encoder.position"] == "m"
    assert result.summary["solver"]["steps"] > 0


def test_overrides_make_a_new_scenario_and_are_checked(root):
    base = fig05b(root)
    damped = base.with_overrides({"controller.c": 400.0, "overrides.bearing_friction.f_s": 6.8})
    assert base.overrides == {}
    assert damped.overrides == {"controller.c": 400.0, "overrides.bearing_friction.f_s": 6.8}
    values = {p["path"]: p for p in damped.parameters()}
    assert values["controller.c"]["value"] == 400.0
    assert values["controller.c"]["unit"] == "N.s/m"
    assert values["overrides.bearing_friction.f_s"]["value"] == 6.8
    with pytest.raises(fistage.LoadError, match="controller.c"):
        base.with_overrides({"controller.c": -1.0})
    with pytest.raises(fistage.Error, match="nope"):
        base.with_overrides({"overrides.nope.k_x": 1.0})
    # More damping settles Fig. 5b's oscillation into a far smaller one.
    steady = damped.run().summary["signals"]["encoder.position"]["peak_to_peak"]
    assert steady < 1e-6, steady


def test_scenarios_from_text_resolve_against_base_dir(root):
    text = (root / "scenarios/paper/fig05b_rigid.toml").read_text()
    scenario = fistage.Scenario.from_toml(text, base_dir=root / "scenarios/paper")
    assert scenario.title.startswith("Fig. 5b")
    with pytest.raises(fistage.LoadError, match="robot"):
        fistage.Scenario.from_toml(text, base_dir=root)
    with pytest.raises(fistage.LoadError, match="duration"):
        fistage.Scenario.from_toml(text.replace("duration = 5.0", "duration = -1.0"),
                                   base_dir=root / "scenarios/paper")


def _peak(scenario):
    return scenario.run().summary["signals"]["encoder.position"]["peak_to_peak"]


def test_scenarios_pickle_and_map_over_processes(root):
    base = fig05b(root)
    again = pickle.loads(pickle.dumps(base.with_overrides({"controller.c": 120.0})))
    assert again.overrides == {"controller.c": 120.0}
    variants = [base.with_overrides({"controller.c": c}) for c in (80.0, 100.0, 120.0)]
    serial = [_peak(v) for v in variants]
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        parallel = list(pool.map(_peak, variants))
    assert parallel == serial


def test_errors_name_what_is_wrong(root):
    with pytest.raises(fistage.LoadError, match="no_such_file"):
        fistage.load(root / "no_such_file.toml")
    result = fig05b(root).run(rtol=1e-6)
    with pytest.raises(KeyError, match="encoder.position"):
        result["encoder.nope"]
    with pytest.raises(fistage.Error, match="engine"):
        fig05b(root).run(engine="euler")
    with pytest.raises(fistage.Error, match="rtol"):
        fig05b(root).run(rtol=2.0)


def test_tighter_tolerance_converges(root):
    loose = fig05b(root).run(rtol=1e-6)["encoder.position"]
    tight = fig05b(root).run(rtol=1e-10)["encoder.position"]
    tighter = fig05b(root).run(rtol=1e-11)["encoder.position"]
    # Over the first 0.5 s (before the limit cycle's phase drifts apart).
    n = 500
    assert numpy.max(numpy.abs(tight[:n] - tighter[:n])) < numpy.max(numpy.abs(loose[:n] - tighter[:n]))


def test_pandas_frame_when_pandas_is_installed(root):
    pandas = pytest.importorskip("pandas")
    frame = fig05b(root).run().to_pandas()
    assert isinstance(frame, pandas.DataFrame)
    assert frame.attrs["units"]["encoder.position"] == "m"
    assert len(frame) == 5001


def test_modes_give_the_program_s_verdict(root):
    modes = fig05b(root).modes()
    # Fig. 5b's FI stage: the slipping equilibrium is linearly stable (the
    # limit cycle beside it is the bistable case, RESULTS.md).
    assert modes["verdict"] == "stable" and modes["stable"]
    assert modes["max_real_part"] < 0
    eigenvalues = modes["eigenvalues"]
    assert eigenvalues.dtype == numpy.complex128
    assert numpy.max(eigenvalues.real) == pytest.approx(modes["max_real_part"], rel=1e-9)
    assert len(modes["frequency_hz"]) == len(modes["modes"])
    sticking = fig05b(root).modes("sticking")
    assert sticking["equilibrium"] == "sticking"
    with pytest.raises(fistage.Error, match="sticking"):
        fig05b(root).modes("sliding")


def test_progress_is_reported_and_a_raising_callback_stops_the_run(root):
    scenario = fistage.load(root / "scenarios/paper/fig05b_fi.toml")
    seen = []
    scenario.run(progress=seen.append)
    assert seen and seen[-1] == 1.0 and seen == sorted(seen)

    def stop(fraction):
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        scenario.run(progress=stop)


def test_ctrl_c_stops_a_long_run(root, ctrl_c):
    import os
    import signal
    import threading
    import time

    text = (root / "scenarios/paper/fig05b_fi.toml").read_text()
    long = fistage.Scenario.from_toml(text.replace("duration = 5.0", "duration = 2000.0"),
                                      base_dir=root / "scenarios/paper")
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        long.run()
    timer.join()
    assert time.monotonic() - start < 2.5


def test_a_result_shows_its_page_in_jupyter_and_writes_it(root, tmp_path):
    result = fig05b(root).run()
    html = result._repr_html_()
    # One frame holding the whole page: its data and the plots' library, no
    # script or style sheet to fetch (the browser test opens such pages).
    assert html.startswith("<iframe srcdoc=") and html.count("<iframe") == 1
    assert "fistage-report-data" in html and "Plotly" in html
    assert "<script src=" not in html and "<link " not in html
    page = tmp_path / "run.html"
    result.report(page)
    text = page.read_text()
    assert text.startswith("<!DOCTYPE html>")
    # The page's summary table holds the run's statistics.
    p2p = result.summary["signals"]["encoder.position"]["peak_to_peak"]
    assert f"{p2p:.3e}".replace("e-05", "e-5") in text


def test_modes_and_studies_show_their_pages(root, tmp_path):
    stage = fistage.load(root / "scenarios/coupling/symmetric_fig05b.toml")
    modes = stage.modes("slipping")
    # Still the dict it was, now with a page: the 3D view's data and its modes.
    assert isinstance(modes, dict) and modes["verdict"] == "unstable"
    html = modes._repr_html_()
    assert html.startswith("<iframe srcdoc=") and "&quot;type&quot;:&quot;scene&quot;" in html
    modes.report(tmp_path / "modes.html")
    assert "fistage-report-data" in (tmp_path / "modes.html").read_text()
    population = fistage.load(root / "scenarios/robust/four_bearing_population.toml")
    study = population.robust(samples=16, threads=1)
    page = study._repr_html_()
    assert "P(linearly unstable)" in page
    estimate = study.summary["p_unstable_linear"]["estimate"]
    assert len(study) == 16 and 0.0 <= estimate <= 1.0
