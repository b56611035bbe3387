//! Drawing an identified stage from its fit (`[robust] from_fit`), against
//! answers known without it:
//!
//! * the drawn values have the fit's mean and covariance (sample moments
//!   inside their sampling error);
//! * P(unstable) of the rigid PD stage whose servo gains carry a correlated
//!   uncertainty equals a plain Monte Carlo over the same covariance made
//!   here with another generator (ChaCha, Box-Muller, a Cholesky factor) and
//!   another stability test (the paper's analytic Routh-Hurwitz conditions,
//!   not the study's eigenvalues), within the two estimates' sampling error;
//! * `replicates` draws each jackknife replicate, spread by sqrt(G - 1),
//!   with equal probability;
//! * what does not fit is named: an undetermined parameter, a path that
//!   names nothing, a matrix that is no covariance, a parameter drawn twice.

use std::path::{Path, PathBuf};

use fistage_analysis::robust::{RobustSpec, Summary};
use fistage_analysis::routh::{RigidStage, rigid_slipping};
use fistage_model::{Loaded, RobotSpec, Scenario, assemble};
use rand::{Rng, SeedableRng};

use crate::robust::routh_boundary;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fistage-from-fit-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The rigid PD stage over a platform at 20 mm/s with this `[robust]`
/// table, as a scenario file in `dir` (so `from_fit` is read from there).
/// The study's spec is None without a `[robust]` table.
fn study(dir: &Path, robust: &str) -> Result<(Loaded, RobotSpec, Option<RobustSpec>), String> {
    let text = format!(
        "robot = {:?}\nduration = 1.0\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1e5\nc = 250\n{robust}",
        root()
            .join("robots/stage_1dof_rigid.urdf")
            .display()
            .to_string()
    );
    let scenario =
        Scenario::from_str(&text, &dir.join("robust.toml")).map_err(|e| e.to_string())?;
    let robot_file = RobotSpec::from_file(&scenario.robot).map_err(|e| e.to_string())?;
    let (robot, model) = assemble(robot_file.clone(), &scenario).map_err(|e| e.to_string())?;
    let spec = match scenario.robust {
        Some(_) => Some(
            RobustSpec::from_scenario(&scenario, &robot_file, None, None)
                .map_err(|e| e.to_string())?,
        ),
        None => None,
    };
    let loaded = Loaded {
        scenario,
        robot,
        model,
    };
    Ok((loaded, robot_file, spec))
}

/// A fit.json over the given paths: values, SI covariance and replicates.
fn write_fit(
    dir: &Path,
    paths: &[&str],
    values: &[f64],
    matrix: &[Vec<f64>],
    replicates: &[Vec<f64>],
) {
    let log: Vec<Vec<f64>> = (0..values.len())
        .map(|i| {
            (0..values.len())
                .map(|j| matrix[i][j] / (values[i] * values[j]))
                .collect()
        })
        .collect();
    let json = serde_json::json!({
        "kind": "record",
        "not_identifiable": [],
        "covariance": {
            "parameters": paths.iter().map(|p| p.rsplit('.').next().unwrap()).collect::<Vec<_>>(),
            "paths": paths,
            "values": values,
            "matrix": matrix,
            "log_matrix": log,
            "method": "made by the test",
            "degrees_of_freedom": replicates.len().saturating_sub(1),
        },
        "replicates": replicates,
    });
    std::fs::write(
        dir.join("fit.json"),
        serde_json::to_string_pretty(&json).unwrap(),
    )
    .unwrap();
}

/// The two gains' uncertainty: c about the stability boundary, k about its
/// nominal, correlated.
fn gains_covariance(c_star: f64) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (mean_c, sd_c) = (c_star, 0.2 * c_star);
    let (mean_k, sd_k) = (1e5, 1.5e4);
    let rho = 0.6;
    (
        vec![mean_c, mean_k],
        vec![
            vec![sd_c * sd_c, rho * sd_c * sd_k],
            vec![rho * sd_c * sd_k, sd_k * sd_k],
        ],
    )
}

/// The paper's Routh-Hurwitz verdict of the rigid stage at gains (k, c).
fn analytic_stable(loaded: &Loaded, k: f64, c: f64) -> bool {
    let model = &loaded.model;
    rigid_slipping(&RigidStage {
        mass: model.bodies()[0].mass,
        k,
        c,
        lugre: model.frictions()[0].lugre,
        platform_velocity: 0.02,
    })
    .stable
}

const FROM_FIT: &str =
    "[robust]\nsamples = 4000\nseed = 5\nsampling = \"random\"\nfrom_fit = \"fit.json\"\n";

#[test]
fn draws_have_the_fit_mean_and_covariance() {
    let dir = scratch("moments");
    let (nominal, _, _) = study(&dir, "").unwrap();
    let (mean, cov) = gains_covariance(routh_boundary(&nominal));
    write_fit(&dir, &["controller.c", "controller.k"], &mean, &cov, &[]);
    let spec = study(&dir, FROM_FIT).unwrap().2.unwrap();
    let columns: Vec<&str> = spec.columns().iter().map(|t| t.path.as_str()).collect();
    assert_eq!(columns, ["controller.c", "controller.k"]);
    let n = spec.samples;
    let draws: Vec<Vec<f64>> = (0..n).map(|i| spec.values(i)).collect();
    let sample_mean: Vec<f64> = (0..2)
        .map(|j| draws.iter().map(|d| d[j]).sum::<f64>() / n as f64)
        .collect();
    for j in 0..2 {
        let tolerance = 4.0 * (cov[j][j] / n as f64).sqrt();
        assert!(
            (sample_mean[j] - mean[j]).abs() < tolerance,
            "mean {j}: {} against {} (+- {tolerance})",
            sample_mean[j],
            mean[j]
        );
    }
    for i in 0..2 {
        for j in 0..2 {
            let s: f64 = draws
                .iter()
                .map(|d| (d[i] - sample_mean[i]) * (d[j] - sample_mean[j]))
                .sum::<f64>()
                / (n - 1) as f64;
            // The sampling error of a covariance entry of normal draws.
            let tolerance = 4.0 * ((cov[i][i] * cov[j][j] + cov[i][j].powi(2)) / n as f64).sqrt();
            assert!(
                (s - cov[i][j]).abs() < tolerance,
                "cov[{i}][{j}]: {s:e} against {:e} (+- {tolerance:e})",
                cov[i][j]
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn p_unstable_matches_a_plain_monte_carlo_over_the_same_covariance() {
    let dir = scratch("probability");
    let (nominal, _, _) = study(&dir, "").unwrap();
    let (mean, cov) = gains_covariance(routh_boundary(&nominal));
    write_fit(&dir, &["controller.c", "controller.k"], &mean, &cov, &[]);
    let (loaded, robot_file, spec) = study(&dir, FROM_FIT).unwrap();
    let spec = spec.unwrap();
    let indices: Vec<usize> = (0..spec.samples).collect();
    let results = spec.run(&loaded, &robot_file, &indices, 2, &|_, _| {});
    let summary = Summary::of(&spec, &results);
    assert_eq!(summary.undetermined_linear + summary.refused, 0);
    let tool = summary
        .p_unstable_linear
        .expect("a linear verdict")
        .estimate;

    // The same covariance drawn here: Cholesky factor, Box-Muller normals.
    let l00 = cov[0][0].sqrt();
    let l10 = cov[1][0] / l00;
    let l11 = (cov[1][1] - l10 * l10).sqrt();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261207);
    let n = 4000;
    let mut unstable = 0;
    for _ in 0..n {
        let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        let radius = (-2.0 * u1.ln()).sqrt();
        let (z0, z1) = (
            radius * (std::f64::consts::TAU * u2).cos(),
            radius * (std::f64::consts::TAU * u2).sin(),
        );
        let c = mean[0] + l00 * z0;
        let k = mean[1] + l10 * z0 + l11 * z1;
        unstable += usize::from(!analytic_stable(&loaded, k, c));
    }
    let plain = unstable as f64 / n as f64;
    let p = 0.5 * (tool + plain);
    let allowed = 3.0 * (p * (1.0 - p) * (2.0 / n as f64)).sqrt();
    println!(
        "P(unstable): from_fit {tool:.4}, plain Monte Carlo {plain:.4} (allowed {allowed:.4})"
    );
    assert!(
        plain > 0.2 && plain < 0.8,
        "the uncertainty straddles the boundary: {plain}"
    );
    assert!((tool - plain).abs() < allowed, "{tool} against {plain}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn replicates_are_drawn_each_with_equal_probability() {
    let dir = scratch("replicates");
    let mean = [250.0, 1e5];
    let replicates = vec![
        vec![255.0, 1.01e5],
        vec![246.0, 0.99e5],
        vec![251.0, 1.02e5],
        vec![248.0, 0.98e5],
    ];
    let cov = vec![vec![20.0, 0.0], vec![0.0, 2e6]];
    write_fit(
        &dir,
        &["controller.c", "controller.k"],
        &mean,
        &cov,
        &replicates,
    );
    let robust = format!("{FROM_FIT}from_fit_draw = \"replicates\"\n");
    let spec = study(&dir, &robust).unwrap().2.unwrap();
    let g = replicates.len();
    let spread = |b: usize| -> Vec<f64> {
        (0..2)
            .map(|j| mean[j] * ((g as f64 - 1.0).sqrt() * (replicates[b][j] / mean[j]).ln()).exp())
            .collect()
    };
    let mut counts = vec![0usize; g];
    for i in 0..spec.samples {
        let v = spec.values(i);
        let b = (0..g)
            .find(|&b| {
                spread(b)
                    .iter()
                    .zip(&v)
                    .all(|(a, x)| (a - x).abs() <= 1e-9 * a.abs())
            })
            .unwrap_or_else(|| panic!("sample {i} ({v:?}) is no spread replicate"));
        counts[b] += 1;
    }
    let expected = spec.samples as f64 / g as f64;
    let sd = (spec.samples as f64 * (1.0 / g as f64) * (1.0 - 1.0 / g as f64)).sqrt();
    for (b, &c) in counts.iter().enumerate() {
        assert!(
            (c as f64 - expected).abs() < 4.0 * sd,
            "replicate {b}: {counts:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn what_does_not_fit_is_named() {
    let dir = scratch("refusals");
    let cov = vec![vec![25.0, 0.0], vec![0.0, 1e6]];
    let refusal = |paths: &[&str], matrix: &[Vec<f64>], extra: &str| -> String {
        write_fit(&dir, paths, &[250.0, 1e5], matrix, &[]);
        match study(&dir, &format!("{FROM_FIT}{extra}")) {
            Ok(_) => panic!("accepted {paths:?} {matrix:?} {extra}"),
            Err(e) => e,
        }
    };
    let e = refusal(&["controller.c", "controller.nonsense"], &cov, "");
    assert!(
        e.contains("fit.json") && e.contains("covariance.paths[1]"),
        "{e}"
    );
    let asymmetric = vec![vec![25.0, 10.0], vec![0.0, 1e6]];
    let e = refusal(&["controller.c", "controller.k"], &asymmetric, "");
    assert!(e.contains("not symmetric"), "{e}");
    let negative = vec![vec![25.0, 1e4], vec![1e4, 1e6]];
    let e = refusal(&["controller.c", "controller.k"], &negative, "");
    assert!(e.contains("negative eigenvalue"), "{e}");
    let twice =
        "[[robust.parameter]]\nparameter = \"controller.k\"\ndistribution = \"normal\"\nsd = 0.1\n";
    let e = refusal(&["controller.c", "controller.k"], &cov, twice);
    assert!(e.contains("controller.k") && e.contains("too"), "{e}");
    // A parameter its record could not determine.
    write_fit(
        &dir,
        &["controller.c", "controller.k"],
        &[250.0, 1e5],
        &cov,
        &[],
    );
    let path = dir.join("fit.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["not_identifiable"] = serde_json::json!([{"parameter": "k", "reason": "no interval"}]);
    std::fs::write(&path, json.to_string()).unwrap();
    let e = study(&dir, FROM_FIT).map(|_| ()).expect_err("refused");
    assert!(e.contains("k was not determined"), "{e}");
    std::fs::remove_file(&path).unwrap();
    let e = study(&dir, FROM_FIT).map(|_| ()).expect_err("refused");
    assert!(
        e.contains("robust.from_fit") && e.contains("fit.json"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
