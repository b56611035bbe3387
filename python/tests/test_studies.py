"""Scenario.sweep, Scenario.robust and Scenario.export_fmu: the sweep's
linear verdicts agree point by point with Scenario.modes on the same
overrides, the tolerance analysis's summary counts its own samples, and the
FMU holds the scenario's model description and a shared library; shards of the
program and of Python merge into one table either way."""

import os
import zipfile

import numpy
import pytest

import fistage


def small_sweep(root):
    text = (root / "scenarios/paper/fig06a_rigid_vp20.toml").read_text()
    text = text.replace('analysis = "both"', 'analysis = "linear"').replace("points = 24", "points = 4")
    return fistage.Scenario.from_toml(text, base_dir=root / "scenarios/paper")


def test_sweep_agrees_with_modes_point_by_point(root):
    scenario = small_sweep(root)
    calls = []
    study = scenario.sweep(threads=2, progress=lambda done, total: calls.append((done, total)))
    assert len(study) == 16 and study["controller.k"].dtype == numpy.float64
    assert sorted(calls)[-1] == (16, 16)
    for point in study.points:
        one = scenario.with_overrides({"controller.k": point["controller.k"],
                                       "controller.c": point["controller.c"]})
        modes = one.modes()
        assert modes["stable"] == point["stable_linear"], point
        assert modes["max_real_part"] == pytest.approx(point["max_real_eig"], rel=1e-9, abs=1e-9)
    assert set(study["stable_linear"]) == {True, False}, "the grid crosses the stability boundary"


def test_robust_summary_counts_its_samples(root):
    scenario = fistage.load(root / "scenarios/robust/fig05b_population.toml")
    study = scenario.robust(samples=32, seed=3)
    summary = study.summary
    assert summary["samples"] == 32 and summary["seed"] == 3 and len(study) == 32
    unstable = numpy.count_nonzero(study["stable_linear"] == False)  # noqa: E712
    assert summary["p_unstable_linear"]["estimate"] == pytest.approx(unstable / 32)
    low, high = summary["p_unstable_linear"]["ci95"]
    assert low <= unstable / 32 <= high
    nominal = {p["path"]: p["value"] for p in scenario.parameters()}
    k_x = study["overrides.isolator.k_x"]
    assert numpy.all(numpy.abs(k_x / nominal["overrides.isolator.k_x"] - 1.0) <= 0.3 + 1e-12)
    again = scenario.robust(samples=32, seed=3)
    assert numpy.array_equal(again["max_real_eig"], study["max_real_eig"]), "seeded"


def test_robust_draws_a_fit_jointly(root, tmp_path):
    """from_fit draws the fitted parameters with the fit's covariance, here
    the servo's stiffness and the bearing's bristle stiffness of the Fig. 5b
    stage, strongly correlated: the drawn
    columns have the fit's means and correlation within their sampling
    error, and the table's own parameters are drawn beside them."""
    import json

    mean = [6e4, 2.2e6]
    sd = [3e3, 1.1e5]
    rho = 0.8
    matrix = [[sd[0] ** 2, rho * sd[0] * sd[1]], [rho * sd[0] * sd[1], sd[1] ** 2]]
    fit = {
        "covariance": {
            "parameters": ["k", "sigma0"],
            "paths": ["controller.k", "overrides.bearing_friction.sigma0"],
            "values": mean,
            "matrix": matrix,
            "log_matrix": [[matrix[i][j] / (mean[i] * mean[j]) for j in range(2)] for i in range(2)],
            "method": "made by the test",
            "degrees_of_freedom": 0,
        },
        "not_identifiable": [],
    }
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(fit))
    scenario = fistage.load(root / "scenarios/robust/fig05b_population.toml")
    n = 512
    study = scenario.robust(samples=n, seed=2, from_fit=path)
    k, c = study["controller.k"], study["overrides.bearing_friction.sigma0"]
    assert len(study) == n and "overrides.isolator.k_x" in study.columns
    for drawn, m, s in ((k, mean[0], sd[0]), (c, mean[1], sd[1])):
        assert abs(drawn.mean() - m) < 4 * s / n ** 0.5
    r = numpy.corrcoef(k, c)[0, 1]
    assert abs(r - rho) < 4 * (1 - rho ** 2) / n ** 0.5, r
    with pytest.raises(Exception, match="from_fit_draw"):
        scenario.robust(samples=8, from_fit=path, from_fit_draw="bootstrap")


def test_export_fmu_packages_the_scenario(root, tmp_path):
    """The package carries the FMU's library itself: nothing else is needed."""
    scenario = fistage.load(root / "scenarios/paper/fig05b_fi.toml")
    path = scenario.export_fmu(tmp_path / "stage.fmu")
    with zipfile.ZipFile(path) as fmu:
        names = fmu.namelist()
        description = fmu.read("modelDescription.xml").decode()
    assert "modelDescription.xml" in names
    assert any(n.startswith("binaries/linux64/") and n.endswith(".so") for n in names)
    assert "servo_force" in description and 'fmiVersion="2.0"' in description
    assert "<ModelExchange" in description and "<CoSimulation" in description
    path3 = scenario.export_fmu(tmp_path / "stage3.fmu", fmi_version=3)
    with zipfile.ZipFile(path3) as fmu:
        names = fmu.namelist()
        description = fmu.read("modelDescription.xml").decode()
    assert any(n.startswith("binaries/x86_64-linux/") and n.endswith(".so") for n in names)
    assert 'fmiVersion="3.0"' in description and 'causality="independent"' in description
    with pytest.raises(fistage.Error, match="fmi_version must be 2 or 3"):
        scenario.export_fmu(tmp_path / "x.fmu", fmi_version=1)
    with pytest.raises(fistage.Error, match="overrides"):
        scenario.with_overrides({"controller.c": 10.0}).export_fmu(tmp_path / "other.fmu")
    with pytest.raises(fistage.Error, match="not found"):
        scenario.export_fmu(tmp_path / "x.fmu", library=tmp_path / "missing.so")


def test_ctrl_c_stops_a_long_tolerance_analysis(root, ctrl_c):
    import signal
    import threading
    import time

    scenario = fistage.load(root / "scenarios/robust/fig05b_population.toml")
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        scenario.robust(samples=65536, threads=1)
    timer.join()
    assert time.monotonic() - start < 2.5


def test_study_keeps_a_refused_samples_reason():
    """A sample whose stage could not be built carries its reason as text;
    the table around it still reads as numbers and verdicts."""
    table = ("sample,overrides.bearing_friction.f_s,stable_linear,max_real_eig,refused\n"
             "0,1.2e0,true,-3.5e0,\n"
             "1,4e-1,,,f_s must be >= f_c\n")
    study = fistage.Study(table)
    assert study["overrides.bearing_friction.f_s"].dtype == numpy.float64
    assert list(study["refused"]) == [None, "f_s must be >= f_c"]
    assert study.points[1]["refused"] == "f_s must be >= f_c"
    assert study.points[0]["stable_linear"] is True and study.points[1]["stable_linear"] is None
    assert numpy.isnan(study["max_real_eig"][1]) and study["max_real_eig"][0] == -3.5


@pytest.mark.parametrize("threads", [0, 1025, 100000])
def test_threads_follow_the_programs_rule(root, threads):
    # The program refuses --threads outside 1..1024; the package refuses the
    # same values by the same rule, before starting any thread.
    with pytest.raises(fistage.Error, match="threads must be from 1 to 1024"):
        small_sweep(root).sweep(threads=threads)


def test_sweep_shards_merge_and_resume_as_the_program_does(root, tmp_path):
    """Two shards written with out= merge into the whole run's points.csv
    byte for byte; a folder holding one shard resumes into the whole run; a
    killed run's journal with a cut last row is taken up and the cut row
    computed again; a second study of another grid into that folder is
    refused."""
    scenario = small_sweep(root)
    whole = scenario.sweep(out=tmp_path / "whole")
    table = (tmp_path / "whole/points.csv").read_text()
    assert len(whole) == 16 and table.count("\n") == 17
    assert {"points.csv", "points.json", "provenance.json"} <= set(os.listdir(tmp_path / "whole"))
    first = scenario.sweep(out=tmp_path / "s0", shard="0/2")
    second = scenario.sweep(out=tmp_path / "s1", shard=(1, 2))
    assert len(first) == 8 and len(second) == 8
    scenario.sweep(out=tmp_path / "merged", merge=[tmp_path / "s0", tmp_path / "s1"])
    assert (tmp_path / "merged/points.csv").read_text() == table
    resumed = scenario.sweep(out=tmp_path / "s0")
    assert len(resumed) == 16 and (tmp_path / "s0/points.csv").read_text() == table
    lines = table.splitlines(keepends=True)
    journal = tmp_path / ".killed.journal"
    journal.mkdir()
    (journal / "points.partial.csv").write_text("".join(lines[:6]) + lines[6][:-4])
    (journal / "provenance.json").write_text((tmp_path / "whole/provenance.json").read_text())
    scenario.sweep(out=tmp_path / "killed")
    assert (tmp_path / "killed/points.csv").read_text() == table
    assert not journal.exists()
    other = fistage.Scenario.from_toml(
        (root / "scenarios/paper/fig06a_rigid_vp20.toml").read_text()
        .replace('analysis = "both"', 'analysis = "linear"').replace("points = 24", "points = 3"),
        base_dir=root / "scenarios/paper")
    with pytest.raises(fistage.Error, match="made by another sweep"):
        other.sweep(out=tmp_path / "whole")
    assert (tmp_path / "whole/points.csv").read_text() == table
    with pytest.raises(fistage.Error, match="shard"):
        scenario.sweep(shard="2/2")


def test_program_and_python_shards_merge_either_way(root, tmp_path):
    """A shard written by the program and one written by Python are one
    study: each face merges them into the table the other computes whole."""
    import subprocess

    program = root / "target/debug/fistage"
    if not program.exists():
        pytest.skip("SKIPPED: no target/debug/fistage to run (cargo build -p fistage)")
    text = (root / "scenarios/paper/fig06a_rigid_vp20.toml").read_text()
    text = text.replace('analysis = "both"', 'analysis = "linear"').replace("points = 24", "points = 4")
    robot = (root / "robots/stage_1dof_rigid.urdf").as_posix()
    lines = [('robot = "%s"' % robot) if line.startswith("robot =") else line for line in text.splitlines()]
    path = tmp_path / "grid.toml"
    path.write_text("\n".join(lines) + "\n")

    def run(*args):
        done = subprocess.run([str(program), "sweep", str(path), *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr

    scenario = fistage.load(path)
    run("--shard", "0/2", "--out", tmp_path / "p0", "--threads", "1")
    scenario.sweep(shard=(1, 2), out=tmp_path / "p1")
    run("--out", tmp_path / "by_program", "--merge", tmp_path / "p0", "--merge", tmp_path / "p1")
    scenario.sweep(out=tmp_path / "by_python", merge=[tmp_path / "p0", tmp_path / "p1"])
    run("--out", tmp_path / "whole")
    whole = (tmp_path / "whole/points.csv").read_text()
    assert whole.count("\n") == 17
    assert (tmp_path / "by_program/points.csv").read_text() == whole
    assert (tmp_path / "by_python/points.csv").read_text() == whole
