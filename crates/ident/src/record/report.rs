//! The report of a record fit: `fit.json` (the parameters by name, each with
//! `value`, `ci95`, `std_error` and `unit`, as the other fits name them), a
//! table for the terminal, `override.toml`, and the measured-against-
//! simulated CSV.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::data::Record;
use super::fit::RecordFit;
use super::plant::RecordParam;
use crate::covariance::FitCovariance;
use crate::report::{
    DEFAULT_ELEMENT, NotIdentifiable, ParamReport, comment, sig, undetermined, write_override,
};
use crate::stribeck::Loss;
use crate::uncertainty::ResidualStats;

/// The JSON report of `fistage identify record`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordReport {
    /// Always `record`.
    pub kind: String,
    /// The data file.
    pub source: String,
    /// The model: paper Eq. 31.
    pub model: String,
    /// The scenario whose servo drove the plant (a closed-loop record).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closed_loop: Option<String>,
    /// `l2` or `huber`.
    pub loss: Loss,
    /// Coulomb friction.
    pub f_c: ParamReport,
    /// Static friction.
    pub f_s: ParamReport,
    /// Stribeck velocity.
    pub v_s: ParamReport,
    /// Bristle stiffness.
    pub sigma0: ParamReport,
    /// Bristle damping.
    pub sigma1: ParamReport,
    /// Viscous friction.
    pub sigma2: ParamReport,
    /// Moving mass (exact when it was given).
    pub mass: ParamReport,
    /// Whether the mass was fitted.
    pub mass_fitted: bool,
    /// The first estimates found from the record, SI units.
    pub start: BTreeMap<String, f64>,
    /// Standard errors if the residuals were independent (Jacobian only),
    /// for comparison: far too small for a real record.
    pub iid_std_error: BTreeMap<String, Option<f64>>,
    /// How the intervals were found.
    pub interval_method: String,
    /// Position residual statistics, m.
    pub residuals: ResidualStats,
    /// Number of samples, and the record's duration, s.
    pub samples: usize,
    /// Duration, s.
    pub duration: f64,
    /// Segments (rests and motions) used.
    pub segments: usize,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// Right-hand-side evaluations of the plant in all.
    pub rhs_evaluations: u64,
    /// Parameters these data cannot determine (left out of override.toml).
    pub not_identifiable: Vec<NotIdentifiable>,
    /// Things the user should know about this fit.
    pub warnings: Vec<String>,
    /// The joint covariance of the fitted parameters, when the fit has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance: Option<FitCovariance>,
    /// The jackknife's replicates: per block of the record left out, the
    /// fitted parameters (in `covariance.parameters` order, SI units).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub replicates: Vec<Vec<f64>>,
}

impl RecordReport {
    /// The report of a fit of `record`.
    pub fn new(record: &Record, fit: &RecordFit) -> Self {
        let param = |p: RecordParam| ParamReport::new(&fit.estimate(p), p.unit());
        let mass_fitted = fit.free.contains(&RecordParam::Mass);
        let mut reports: Vec<(&str, ParamReport)> = RecordParam::ALL
            .iter()
            .map(|&p| (p.name(), param(p)))
            .collect();
        let checked: Vec<(&str, &ParamReport)> = reports
            .iter()
            .filter(|(name, _)| mass_fitted || *name != "mass")
            .map(|(n, p)| (*n, p))
            .collect();
        let mut not_identifiable = undetermined(&checked);
        for (p, value) in RecordParam::ALL.iter().map(|&p| (p, fit.theta.get(p))) {
            let (low, high) = fit.bounds[p.index()];
            let on_box = value <= 1.01 * low || value >= high / 1.01;
            if fit.free.contains(&p)
                && on_box
                && !not_identifiable.iter().any(|n| n.parameter == p.name())
            {
                not_identifiable.push(NotIdentifiable {
                    parameter: p.name().into(),
                    reason: format!(
                        "the fit ran to the edge of its box [{}, {}] around its start: the \
                         record does not hold it",
                        sig(low),
                        sig(high)
                    ),
                });
            }
        }
        if !fit.converged {
            for p in &fit.free {
                if !not_identifiable.iter().any(|n| n.parameter == p.name()) {
                    not_identifiable.push(NotIdentifiable {
                        parameter: p.name().into(),
                        reason: format!(
                            "the fit did not converge in {} iterations",
                            fit.iterations
                        ),
                    });
                }
            }
        }
        let warnings: Vec<String> = fit.start.notes.clone();
        let take = |name: &str, reports: &mut Vec<(&str, ParamReport)>| {
            let i = reports.iter().position(|(n, _)| *n == name).unwrap_or(0);
            reports.remove(i).1
        };
        Self {
            kind: "record".into(),
            source: record.source.clone(),
            model: match &fit.closed_loop {
                None => "paper Eq. 31: M x'' = -(sigma0 z + sigma1 z' + sigma2 x') + f, LuGre z",
                Some(_) => {
                    "paper Eq. 31: M x'' = -(sigma0 z + sigma1 z' + sigma2 x') + f, LuGre z, f \
                     the scenario's servo on the simulated encoder (closed loop)"
                }
            }
            .into(),
            closed_loop: fit.closed_loop.clone(),
            loss: fit.loss,
            f_c: take("f_c", &mut reports),
            f_s: take("f_s", &mut reports),
            v_s: take("v_s", &mut reports),
            sigma0: take("sigma0", &mut reports),
            sigma1: take("sigma1", &mut reports),
            sigma2: take("sigma2", &mut reports),
            mass: take("mass", &mut reports),
            mass_fitted,
            start: RecordParam::ALL
                .iter()
                .map(|p| (p.name().to_string(), fit.start.theta.get(*p)))
                .collect(),
            iid_std_error: fit
                .free
                .iter()
                .zip(&fit.iid_std_errors)
                .map(|(p, se)| (p.name().to_string(), *se))
                .collect(),
            interval_method: format!(
                "delete-one-block jackknife over {} blocks of consecutive residuals, Student t \
                 with {} degrees of freedom",
                fit.blocks,
                fit.blocks.saturating_sub(1)
            ),
            residuals: fit.residuals.clone(),
            samples: record.len(),
            duration: record.duration(),
            segments: fit.segments.len(),
            iterations: fit.iterations,
            rhs_evaluations: fit.rhs_evaluations,
            not_identifiable,
            warnings,
            covariance: covariance_of(fit, DEFAULT_ELEMENT),
            replicates: fit.replicates(),
        }
    }

    /// The report with the parameter paths of the friction element
    /// `element` (the one `override.toml` writes).
    pub fn for_element(mut self, element: &str) -> Self {
        if let Some(covariance) = &mut self.covariance {
            covariance.paths = covariance
                .parameters
                .iter()
                .map(|name| path_of(name, element))
                .collect();
        }
        self
    }

    /// The parameters in the order of [`RecordParam::ALL`].
    pub fn params(&self) -> [(&'static str, &ParamReport); 7] {
        [
            ("f_c", &self.f_c),
            ("f_s", &self.f_s),
            ("v_s", &self.v_s),
            ("sigma0", &self.sigma0),
            ("sigma1", &self.sigma1),
            ("sigma2", &self.sigma2),
            ("mass", &self.mass),
        ]
    }

    /// A plain-text table of the fit.
    pub fn table(&self) -> String {
        let mut out = format!(
            "Record fit of {} ({} samples over {:.3} s, {} segments, {} loss)\n",
            self.source,
            self.samples,
            self.duration,
            self.segments,
            self.loss.name()
        );
        let _ = writeln!(
            out,
            "{:<8} {:>13} {:>29} {:>12} {:>12} {:>13}  unit",
            "param", "value", "95% interval", "std error", "iid s.e.", "start"
        );
        for (name, p) in self.params() {
            let interval = p.ci95.map_or("-".to_string(), |[a, b]| {
                format!("[{}, {}]", sig(a), sig(b))
            });
            let iid = self
                .iid_std_error
                .get(name)
                .copied()
                .flatten()
                .map_or("-".into(), sig);
            let _ = writeln!(
                out,
                "{name:<8} {:>13} {interval:>29} {:>12} {iid:>12} {:>13}  {}",
                sig(p.value),
                p.std_error.map_or("-".into(), sig),
                sig(self.start.get(name).copied().unwrap_or(f64::NAN)),
                p.unit
            );
        }
        let _ = writeln!(
            out,
            "position residual: rms {} m, max {} m; {} iterations, {} plant evaluations",
            sig(self.residuals.rms),
            sig(self.residuals.max_abs),
            self.iterations,
            self.rhs_evaluations
        );
        let _ = writeln!(out, "intervals: {}", self.interval_method);
        for n in &self.not_identifiable {
            let _ = writeln!(out, "not identifiable: {} ({})", n.parameter, n.reason);
        }
        for w in &self.warnings {
            let _ = writeln!(out, "warning: {w}");
        }
        out
    }
}

/// The parameter-table path of a record parameter of the friction element
/// `element`: the six LuGre ones; the moving mass has none.
fn path_of(name: &str, element: &str) -> Option<String> {
    (name != RecordParam::Mass.name()).then(|| format!("overrides.{element}.{name}"))
}

/// The fit's joint covariance as `fit.json` carries it.
fn covariance_of(fit: &RecordFit, element: &str) -> Option<FitCovariance> {
    let joint = fit.joint.as_ref()?;
    let matrix = fit.covariance()?;
    let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
        m.row_iter().map(|r| r.iter().copied().collect()).collect()
    };
    let parameters: Vec<String> = fit.free.iter().map(|p| p.name().to_string()).collect();
    Some(FitCovariance {
        paths: parameters.iter().map(|n| path_of(n, element)).collect(),
        values: fit.free.iter().map(|&p| fit.theta.get(p)).collect(),
        matrix: rows(&matrix),
        log_matrix: rows(&joint.log_covariance),
        method: format!(
            "linearised delete-one-block jackknife over {} blocks, in ln(theta); \
             matrix = diag(theta) log_matrix diag(theta)",
            fit.blocks
        ),
        degrees_of_freedom: joint.degrees_of_freedom,
        parameters,
    })
}

/// The six LuGre parameters as `[overrides.<element>]` (the mass is a
/// property of the robot file, so it is a comment).
pub fn record_override(element: &str, report: &RecordReport) -> String {
    let mut out = format!(
        "# LuGre friction identified from the record {} (output error, {} loss, {} samples).\n",
        comment(&report.source),
        report.loss.name(),
        report.samples
    );
    let _ = writeln!(
        out,
        "# Moving mass {} {} ({}).",
        sig(report.mass.value),
        report.mass.unit,
        if report.mass_fitted {
            "fitted"
        } else {
            "given"
        }
    );
    let params = report.params();
    write_override(&mut out, element, &params[..6], &report.not_identifiable);
    out
}

/// `t_s,force_N,measured_m,simulated_m,residual_m` at every sample.
pub fn record_fit_csv(record: &Record, fit: &RecordFit) -> String {
    let mut out = String::from("t_s,force_N,measured_m,simulated_m,residual_m\n");
    for k in 0..record.len() {
        let (x, s) = (record.position[k], fit.simulated[k]);
        let _ = writeln!(
            out,
            "{},{},{},{},{}",
            record.time[k],
            record.force[k],
            x,
            s,
            s - x
        );
    }
    out
}
