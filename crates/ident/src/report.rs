//! Reports of fits: serde structs for the JSON output, a plain-text table, and
//! the fitted parameters as a friction-element override that a scenario can
//! include (`[overrides.<element>]` with the LuGre keys, SI units).
//!
//! JSON shape (every parameter in SI units with its 95% interval):
//!
//! ```json
//! {"kind": "stribeck", "source": "fss.csv", "loss": "l2",
//!  "f_c": {"value": 5.1, "ci95": [5.05, 5.15], "std_error": 0.025, "unit": "N"},
//!  "f_s": {...}, "v_s": {...}, "sigma2": {...}, "residuals": {...}, ...}
//! ```

use std::fmt::Write as _;

use fistage_model::LugreParams;
use serde::{Deserialize, Serialize};

use crate::frf::{FrfData, FrfFit, FrfResiduals};
use crate::stribeck::{AsymmetricFit, AsymmetryTest, Loss, StribeckData, StribeckFit};
use crate::uncertainty::{Estimate, ResidualStats};

/// The default name of the friction element an override applies to.
pub const DEFAULT_ELEMENT: &str = "bearing_friction";

/// One parameter in a report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamReport {
    /// Estimate, SI units.
    pub value: f64,
    /// 95% confidence interval, SI units (`null` if the data do not determine it).
    pub ci95: Option<[f64; 2]>,
    /// Standard error, SI units.
    pub std_error: Option<f64>,
    /// SI unit of the value.
    pub unit: String,
}

/// A parameter the data cannot determine, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NotIdentifiable {
    /// The parameter (`f_c`, `v_s`, `sigma0`, ...).
    pub parameter: String,
    /// Why: no interval (a singular or ill-conditioned Jacobian), an
    /// interval wider than the value, or an estimate on its bound.
    pub reason: String,
}

impl NotIdentifiable {
    fn new(parameter: &str, reason: String) -> Self {
        Self {
            parameter: parameter.to_string(),
            reason,
        }
    }
}

/// The parameters among `params` that the data do not determine.
pub(crate) fn undetermined(params: &[(&str, &ParamReport)]) -> Vec<NotIdentifiable> {
    params
        .iter()
        .filter_map(|(name, p)| {
            p.undetermined()
                .or_else(|| on_bound(name, p.value))
                .map(|why| NotIdentifiable::new(name, why))
        })
        .collect()
}

/// An estimate on the bound of its LuGre key's rule (the fits keep every
/// parameter >= 0; sigma0, f_c, f_s and v_s must be > 0).
fn on_bound(name: &str, value: f64) -> Option<String> {
    let key = LugreParams::key(name)?;
    (value <= 0.0).then(|| {
        format!(
            "the estimate {} sits on its bound (it must be {})",
            sig(value),
            key.rule.requirement()
        )
    })
}

impl ParamReport {
    /// Why the data do not determine this parameter, if they do not.
    pub fn undetermined(&self) -> Option<String> {
        if !self.value.is_finite() {
            return Some(format!("its estimate is {}", self.value));
        }
        let (Some([lo, hi]), Some(se)) = (self.ci95, self.std_error) else {
            return Some("no interval: the Jacobian is singular or ill-conditioned".into());
        };
        if !(lo.is_finite() && hi.is_finite() && se.is_finite()) {
            return Some("its interval is not finite".into());
        }
        if 0.5 * (hi - lo) > self.value.abs() {
            return Some(format!(
                "its 95% interval [{}, {}] is wider than the value {}",
                sig(lo),
                sig(hi),
                sig(self.value)
            ));
        }
        None
    }

    pub(crate) fn new(estimate: &Estimate, unit: &str) -> Self {
        Self {
            value: estimate.value,
            ci95: estimate.ci95,
            std_error: estimate.std_error,
            unit: unit.to_string(),
        }
    }
}

/// The Stribeck parameters of one fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BranchReport {
    /// Coulomb friction.
    pub f_c: ParamReport,
    /// Static friction.
    pub f_s: ParamReport,
    /// Stribeck velocity.
    pub v_s: ParamReport,
    /// Viscous friction.
    pub sigma2: ParamReport,
    /// Residual statistics (N).
    pub residuals: ResidualStats,
}

impl BranchReport {
    fn new(fit: &StribeckFit) -> Self {
        Self {
            f_c: ParamReport::new(&fit.f_c, "N"),
            f_s: ParamReport::new(&fit.f_s, "N"),
            v_s: ParamReport::new(&fit.v_s, "m/s"),
            sigma2: ParamReport::new(&fit.sigma2, "N s/m"),
            residuals: fit.residuals.clone(),
        }
    }
}

/// The asymmetry part of a Stribeck report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AsymmetryReport {
    /// Fit of the branch v > 0.
    pub positive: BranchReport,
    /// Fit of the branch v < 0 (magnitudes).
    pub negative: BranchReport,
    /// The test between the branches (its fields appear flat in the JSON).
    #[serde(flatten)]
    pub test: AsymmetryTest,
}

/// The JSON report of `fistage identify stribeck`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StribeckReport {
    /// Always `stribeck`.
    pub kind: String,
    /// The data file.
    pub source: String,
    /// `l2`, `huber` or `l1`.
    pub loss: Loss,
    /// Huber threshold, N.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub huber_delta: Option<f64>,
    /// Coulomb friction (both branches).
    pub f_c: ParamReport,
    /// Static friction (both branches).
    pub f_s: ParamReport,
    /// Stribeck velocity (both branches).
    pub v_s: ParamReport,
    /// Viscous friction (both branches).
    pub sigma2: ParamReport,
    /// Residual statistics, N.
    pub residuals: ResidualStats,
    /// Range of v_s searched, m/s.
    pub v_s_search: [f64; 2],
    /// Per-branch fits and the asymmetry test, when asked for.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub asymmetry: Option<AsymmetryReport>,
    /// Parameters these data cannot determine (left out of override.toml).
    #[serde(default)]
    pub not_identifiable: Vec<NotIdentifiable>,
    /// Things the user should know about this fit.
    pub warnings: Vec<String>,
}

impl StribeckReport {
    /// The report of a fit, with the asymmetry analysis when there is one.
    pub fn new(source: &str, fit: &StribeckFit, asymmetric: Option<&AsymmetricFit>) -> Self {
        let branch = BranchReport::new(fit);
        let asymmetry = asymmetric.map(|a| AsymmetryReport {
            positive: BranchReport::new(&a.positive),
            negative: BranchReport::new(&a.negative),
            test: a.test.clone(),
        });
        let mut not_identifiable = undetermined(&[
            ("f_c", &branch.f_c),
            ("f_s", &branch.f_s),
            ("v_s", &branch.v_s),
            ("sigma2", &branch.sigma2),
        ]);
        let flagged =
            |list: &[NotIdentifiable], name: &str| list.iter().any(|n| n.parameter == name);
        // f_s on its bound f_c: no Stribeck dip in the data, so no v_s either.
        if branch.f_s.value - branch.f_c.value <= 1e-9 * branch.f_s.value.abs()
            && !flagged(&not_identifiable, "v_s")
        {
            not_identifiable.push(NotIdentifiable::new(
                "v_s",
                "f_s sits on its bound f_s = f_c: the data show no Stribeck effect".into(),
            ));
        }
        let [low, high] = fit.v_s_search;
        let v_s = branch.v_s.value;
        if (v_s <= low * (1.0 + 1e-6) || v_s >= high * (1.0 - 1e-6))
            && !flagged(&not_identifiable, "v_s")
        {
            not_identifiable.push(NotIdentifiable::new(
                "v_s",
                format!(
                    "on the edge of the searched range [{}, {}] m/s",
                    sig(low),
                    sig(high)
                ),
            ));
        }
        Self {
            kind: "stribeck".to_string(),
            source: source.to_string(),
            loss: fit.loss,
            huber_delta: fit.huber_delta,
            f_c: branch.f_c,
            f_s: branch.f_s,
            v_s: branch.v_s,
            sigma2: branch.sigma2,
            residuals: fit.residuals.clone(),
            v_s_search: fit.v_s_search,
            asymmetry,
            not_identifiable,
            warnings: stribeck_warnings(fit, asymmetric),
        }
    }

    /// A plain-text table of the fit.
    pub fn table(&self) -> String {
        let mut out = format!(
            "Stribeck fit of {} ({} points, {} loss{})\n",
            self.source,
            self.residuals.n,
            self.loss_name(),
            self.huber_delta
                .map_or(String::new(), |d| format!(", threshold {} N", sig(d)))
        );
        out.push_str(&table_header());
        for (name, p) in [
            ("f_c", &self.f_c),
            ("f_s", &self.f_s),
            ("v_s", &self.v_s),
            ("sigma2", &self.sigma2),
        ] {
            out.push_str(&table_row(name, p));
        }
        out.push_str(&residual_line(&self.residuals, "N"));
        if self.loss != Loss::L2 && !self.residuals.suspected_outliers.is_empty() {
            let _ = writeln!(
                out,
                "outliers (down-weighted): lines {}",
                join_lines(&self.residuals.suspected_outliers)
            );
        }
        if let Some(a) = &self.asymmetry {
            let _ = writeln!(out, "\nPer-branch fits (negative branch as magnitudes):");
            let _ = writeln!(out, "{:<8} {:>26} {:>26}", "", "v > 0", "v < 0");
            for (name, pos, neg) in [
                ("f_c", &a.positive.f_c, &a.negative.f_c),
                ("f_s", &a.positive.f_s, &a.negative.f_s),
                ("v_s", &a.positive.v_s, &a.negative.v_s),
                ("sigma2", &a.positive.sigma2, &a.negative.sigma2),
            ] {
                let _ = writeln!(out, "{name:<8} {:>26} {:>26}", value_ci(pos), value_ci(neg));
            }
            let test = &a.test;
            let dof: Vec<String> = test.dof.iter().map(|d| d.to_string()).collect();
            let _ = writeln!(
                out,
                "Asymmetry: {:?} test, statistic {} (dof {}), p = {:.3e}: {}",
                test.test,
                sig(test.statistic),
                dof.join(", "),
                test.p_value,
                if test.significant {
                    format!("significant at {}", test.alpha)
                } else {
                    format!("not significant at {}", test.alpha)
                }
            );
        }
        push_not_identifiable(&mut out, &self.not_identifiable);
        push_warnings(&mut out, &self.warnings);
        out
    }

    fn loss_name(&self) -> &'static str {
        self.loss.name()
    }
}

fn stribeck_warnings(fit: &StribeckFit, asymmetric: Option<&AsymmetricFit>) -> Vec<String> {
    let mut warnings = Vec::new();
    if fit.v_s_at_search_limit {
        warnings.push(format!(
            "v_s is at the end of the searched range [{}, {}] m/s: the data do not determine it",
            sig(fit.v_s_search[0]),
            sig(fit.v_s_search[1])
        ));
    }
    if fit.f_s.value <= fit.f_c.value {
        warnings.push(
            "f_s = f_c: the data show no Stribeck hump, so v_s is not determined".to_string(),
        );
    }
    if fit.loss == Loss::L2 && !fit.residuals.suspected_outliers.is_empty() {
        warnings.push(format!(
            "suspected outliers at lines {}: consider --robust",
            join_lines(&fit.residuals.suspected_outliers)
        ));
    }
    if fit.estimates().iter().any(|e| e.ci95.is_none()) {
        warnings.push(
            "some intervals are unknown: the Jacobian is singular at the optimum".to_string(),
        );
    }
    if let Some(a) = asymmetric
        && a.test.significant
    {
        warnings.push(format!(
            "the branches differ (p = {:.2e}); the override holds the two-sided fit, \
             the per-branch values are in the report",
            a.test.p_value
        ));
    }
    warnings
}

/// The JSON report of `fistage identify frf`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfReport {
    /// Always `frf`.
    pub kind: String,
    /// The data file.
    pub source: String,
    /// Whether the phase was used (complex or magnitude-and-phase data).
    pub used_phase: bool,
    /// Bristle stiffness.
    pub sigma0: ParamReport,
    /// sigma1 + sigma2 as seen by the FRF.
    pub sigma1_plus_sigma2: ParamReport,
    /// Bristle damping, when sigma2 was given.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub sigma1: Option<ParamReport>,
    /// sigma2 as given.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub sigma2: Option<ParamReport>,
    /// Moving mass m_t + m_b.
    pub mass: ParamReport,
    /// Whether the mass was fitted (otherwise it was given and its interval is exact).
    pub mass_fitted: bool,
    /// Residual statistics.
    pub residuals: FrfResiduals,
    /// Parameters these data cannot determine (left out of override.toml).
    #[serde(default)]
    pub not_identifiable: Vec<NotIdentifiable>,
    /// Things the user should know about this fit.
    pub warnings: Vec<String>,
}

impl FrfReport {
    /// The report of an FRF fit.
    pub fn new(source: &str, fit: &FrfFit) -> Self {
        let mut warnings = Vec::new();
        match &fit.sigma1 {
            None => warnings.push(
                "sigma1 is not separated from sigma2: pass --sigma2 (from the Stribeck fit)"
                    .to_string(),
            ),
            Some(s1) if s1.value < 0.0 => warnings.push(format!(
                "sigma1 = {} N s/m < 0: sigma2 exceeds the damping the FRF shows",
                sig(s1.value)
            )),
            Some(_) => {}
        }
        if !fit.residuals.suspected_outliers.is_empty() {
            warnings.push(format!(
                "suspected outliers at lines {}",
                join_lines(&fit.residuals.suspected_outliers)
            ));
        }
        let sigma0 = ParamReport::new(&fit.sigma0, "N/m");
        let sigma1_plus_sigma2 = ParamReport::new(&fit.damping, "N s/m");
        let sigma1 = fit.sigma1.as_ref().map(|e| ParamReport::new(e, "N s/m"));
        let mass = ParamReport::new(&fit.mass, "kg");
        let mut checked = vec![("sigma0", &sigma0), ("sigma1+sigma2", &sigma1_plus_sigma2)];
        if let Some(s1) = &sigma1 {
            checked.push(("sigma1", s1));
        }
        if fit.mass_fitted {
            checked.push(("mass", &mass));
        }
        let not_identifiable = undetermined(&checked);
        Self {
            kind: "frf".to_string(),
            source: source.to_string(),
            used_phase: fit.used_phase,
            sigma0,
            sigma1_plus_sigma2,
            sigma1,
            sigma2: fit.sigma2.as_ref().map(|e| ParamReport::new(e, "N s/m")),
            mass,
            mass_fitted: fit.mass_fitted,
            residuals: fit.residuals.clone(),
            not_identifiable,
            warnings,
        }
    }

    /// A plain-text table of the fit.
    pub fn table(&self) -> String {
        let mut out = format!(
            "FRF fit of {} ({} frequencies, {}; mass {})\n",
            self.source,
            self.residuals.n,
            if self.used_phase {
                "magnitude and phase"
            } else {
                "magnitude only"
            },
            if self.mass_fitted { "fitted" } else { "given" }
        );
        out.push_str(&table_header());
        out.push_str(&table_row("sigma0", &self.sigma0));
        out.push_str(&table_row("sigma1+sigma2", &self.sigma1_plus_sigma2));
        if let Some(s1) = &self.sigma1 {
            out.push_str(&table_row("sigma1", s1));
        }
        if let Some(s2) = &self.sigma2 {
            out.push_str(&table_row("sigma2", s2));
        }
        out.push_str(&table_row("mass", &self.mass));
        let r = &self.residuals;
        let _ = write!(
            out,
            "residuals: magnitude rms {} dB (max {} dB)",
            sig(r.rms_magnitude_db),
            sig(r.max_magnitude_db)
        );
        if let (Some(rms), Some(max)) = (r.rms_phase_deg, r.max_phase_deg) {
            let _ = write!(out, ", phase rms {} deg (max {} deg)", sig(rms), sig(max));
        }
        let _ = writeln!(out, ", R^2 (dB) {:.6}, dof {}", r.r_squared_db, r.dof);
        push_not_identifiable(&mut out, &self.not_identifiable);
        push_warnings(&mut out, &self.warnings);
        out
    }
}

fn table_header() -> String {
    format!(
        "{:<14} {:>14} {:>32}  {}\n",
        "parameter", "value", "95% interval", "unit"
    )
}

fn table_row(name: &str, p: &ParamReport) -> String {
    format!(
        "{name:<14} {:>14} {:>32}  {}\n",
        sig(p.value),
        interval(p.ci95),
        p.unit
    )
}

fn interval(ci: Option<[f64; 2]>) -> String {
    ci.map_or("unknown".to_string(), |[lo, hi]| {
        format!("[{}, {}]", sig(lo), sig(hi))
    })
}

fn value_ci(p: &ParamReport) -> String {
    match p.half_width() {
        Some(h) => format!("{} +- {}", sig(p.value), sig(h)),
        None => sig(p.value),
    }
}

impl ParamReport {
    fn half_width(&self) -> Option<f64> {
        self.ci95.map(|[lo, hi]| 0.5 * (hi - lo))
    }
}

fn residual_line(r: &ResidualStats, unit: &str) -> String {
    format!(
        "residuals: rms {} {unit}, max {} {unit}, robust scale {} {unit}, R^2 {:.6}, dof {}\n",
        sig(r.rms),
        sig(r.max_abs),
        sig(r.robust_scale),
        r.r_squared,
        r.dof
    )
}

fn push_not_identifiable(out: &mut String, list: &[NotIdentifiable]) {
    for item in list {
        let _ = writeln!(
            out,
            "not identifiable: {} ({})",
            item.parameter, item.reason
        );
    }
}

fn push_warnings(out: &mut String, warnings: &[String]) {
    for w in warnings {
        let _ = writeln!(out, "warning: {w}");
    }
}

fn join_lines(lines: &[u64]) -> String {
    lines
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Six significant digits, fixed notation for ordinary magnitudes.
pub(crate) fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.5e}")
    }
}

/// A TOML float that reads back exactly.
fn toml_float(x: f64) -> String {
    format!("{x:?}")
}

pub(crate) fn comment(text: &str) -> String {
    text.replace(['\n', '\r'], " ")
}

/// The Stribeck parameters as `[overrides.<element>]` (f_c, f_s, v_s, sigma2).
pub fn stribeck_override(element: &str, report: &StribeckReport) -> String {
    let mut out = format!(
        "# LuGre steady-state friction identified from {} ({} loss, {} points).\n",
        comment(&report.source),
        report.loss.name(),
        report.residuals.n
    );
    if let Some(a) = &report.asymmetry {
        let _ = writeln!(
            out,
            "# Branches {} (p = {:.2e}); per branch (v > 0 | v < 0):",
            if a.test.significant {
                "differ"
            } else {
                "agree"
            },
            a.test.p_value
        );
        for (name, pos, neg) in [
            ("f_c", &a.positive.f_c, &a.negative.f_c),
            ("f_s", &a.positive.f_s, &a.negative.f_s),
            ("v_s", &a.positive.v_s, &a.negative.v_s),
            ("sigma2", &a.positive.sigma2, &a.negative.sigma2),
        ] {
            let _ = writeln!(
                out,
                "#   {name:<7} {} | {}",
                toml_float(pos.value),
                toml_float(neg.value)
            );
        }
    }
    let params = [
        ("f_c", &report.f_c),
        ("f_s", &report.f_s),
        ("v_s", &report.v_s),
        ("sigma2", &report.sigma2),
    ];
    write_override(&mut out, element, &params, &report.not_identifiable);
    out
}

/// The FRF parameters as `[overrides.<element>]`: sigma0, and sigma1 when sigma2
/// was given. The Stribeck override holds f_c, f_s, v_s and sigma2, so the two
/// are disjoint; given the Stribeck report (`--sigma2-from`), this one holds all
/// six parameters and replaces it.
pub fn frf_override(
    element: &str,
    report: &FrfReport,
    stribeck: Option<&StribeckReport>,
) -> String {
    let mut out = format!(
        "# LuGre pre-motion parameters identified from {} (mass {} kg, {}).\n",
        comment(&report.source),
        toml_float(report.mass.value),
        if report.mass_fitted {
            "fitted"
        } else {
            "given"
        }
    );
    let mut params = vec![("sigma0", &report.sigma0)];
    match &report.sigma1 {
        Some(s1) => params.push(("sigma1", s1)),
        None => {
            let _ = writeln!(
                out,
                "# sigma1 + sigma2 = {} N s/m; sigma1 needs sigma2 (--sigma2), so it is not set here.",
                toml_float(report.sigma1_plus_sigma2.value)
            );
        }
    }
    if let Some(s) = stribeck {
        let _ = writeln!(
            out,
            "# Steady-state parameters from {} ({} loss).",
            comment(&s.source),
            s.loss.name()
        );
        params.extend([
            ("f_c", &s.f_c),
            ("f_s", &s.f_s),
            ("v_s", &s.v_s),
            ("sigma2", &s.sigma2),
        ]);
    }
    let mut not_identifiable = report.not_identifiable.clone();
    not_identifiable.extend(
        stribeck
            .iter()
            .flat_map(|s| s.not_identifiable.iter().cloned()),
    );
    write_override(&mut out, element, &params, &not_identifiable);
    out
}

/// The `[overrides.<element>]` table, written by the TOML serializer (so no
/// element name can break it). Each value passes the parameter table's rule
/// for its LuGre key, or it is left out with a comment saying why.
pub(crate) fn write_override(
    out: &mut String,
    element: &str,
    params: &[(&str, &ParamReport)],
    not_identifiable: &[NotIdentifiable],
) {
    let _ = writeln!(out, "# 95% intervals (SI units):");
    for (name, p) in params {
        let _ = writeln!(out, "#   {name:<7} {} {}", interval(p.ci95), p.unit);
    }
    let mut values = toml::Table::new();
    for (name, p) in params {
        if let Some(item) = not_identifiable.iter().find(|n| n.parameter == *name) {
            let _ = writeln!(
                out,
                "# {name} is not identifiable from these data ({}); not written",
                item.reason
            );
            continue;
        }
        match LugreParams::key(name) {
            Some(key) if key.rule.admits(p.value) => {
                values.insert(key.name.to_string(), toml::Value::Float(p.value));
            }
            Some(key) => {
                let _ = writeln!(
                    out,
                    "# {name} = {} is not written: it must be {}",
                    p.value,
                    key.rule.requirement()
                );
            }
            None => {
                let _ = writeln!(out, "# {name} is not a LuGre parameter; not written");
            }
        }
    }
    let mut overrides = toml::Table::new();
    overrides.insert(element.to_string(), toml::Value::Table(values));
    let mut document = toml::Table::new();
    document.insert("overrides".into(), toml::Value::Table(overrides));
    // A table of tables of floats always serializes.
    out.push_str(&toml::to_string(&document).unwrap_or_default());
}

/// The data with the fitted force at each point:
/// `line,velocity_m_per_s,force_N,fit_force_N,residual_N`.
pub fn stribeck_data_vs_fit_csv(data: &StribeckData, fit: &StribeckFit) -> String {
    let mut out = "line,velocity_m_per_s,force_N,fit_force_N,residual_N\n".to_string();
    for ((v, f), line) in data.velocity.iter().zip(&data.force).zip(&data.lines) {
        let model = fit.predict(*v);
        let _ = writeln!(out, "{line},{v:?},{f:?},{model:?},{:?}", f - model);
    }
    out
}

/// The fitted curve at `points` velocities spanning the data (logarithmically
/// spaced on each sign present): `velocity_m_per_s,fit_force_N`.
pub fn stribeck_curve_csv(data: &StribeckData, fit: &StribeckFit, points: usize) -> String {
    let mut out = "velocity_m_per_s,fit_force_N\n".to_string();
    let signs: Vec<f64> = [-1.0, 1.0]
        .into_iter()
        .filter(|s| data.velocity.iter().any(|v| v * s > 0.0))
        .collect();
    let abs = data.velocity.iter().map(|v| v.abs());
    let (lo, hi) = (
        abs.clone().fold(f64::INFINITY, f64::min),
        abs.fold(0.0, f64::max),
    );
    let per_sign = (points / signs.len().max(1)).max(2);
    for sign in signs {
        let mut speeds = log_spaced(lo, hi, per_sign);
        if sign < 0.0 {
            speeds.reverse();
        }
        for speed in speeds {
            let v = sign * speed;
            let _ = writeln!(out, "{v:?},{:?}", fit.predict(v));
        }
    }
    out
}

/// The data with the fitted response at each frequency:
/// `line,freq_Hz,mag_m_per_N[,phase_deg],fit_mag_m_per_N,fit_phase_deg`.
/// Measured phases are shifted by whole turns to lie next to the model's.
pub fn frf_data_vs_fit_csv(data: &FrfData, fit: &FrfFit) -> String {
    let mut out = if data.has_phase {
        "line,freq_Hz,mag_m_per_N,phase_deg,fit_mag_m_per_N,fit_phase_deg\n".to_string()
    } else {
        "line,freq_Hz,mag_m_per_N,fit_mag_m_per_N,fit_phase_deg\n".to_string()
    };
    for ((w, g), line) in data.omega.iter().zip(&data.response).zip(&data.lines) {
        let model = fit.response(*w);
        let f_hz = w / (2.0 * std::f64::consts::PI);
        let model_phase = model.arg();
        let _ = if data.has_phase {
            let phase = model_phase + (*g / model).arg();
            writeln!(
                out,
                "{line},{f_hz:?},{:?},{:?},{:?},{:?}",
                g.norm(),
                phase.to_degrees(),
                model.norm(),
                model_phase.to_degrees()
            )
        } else {
            writeln!(
                out,
                "{line},{f_hz:?},{:?},{:?},{:?}",
                g.norm(),
                model.norm(),
                model_phase.to_degrees()
            )
        };
    }
    out
}

/// The fitted response at `points` frequencies spanning the data:
/// `freq_Hz,fit_mag_m_per_N,fit_phase_deg`.
pub fn frf_curve_csv(data: &FrfData, fit: &FrfFit, points: usize) -> String {
    let mut out = "freq_Hz,fit_mag_m_per_N,fit_phase_deg\n".to_string();
    let lo = data.omega.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = data.omega.iter().copied().fold(0.0, f64::max);
    for w in log_spaced(lo, hi, points.max(2)) {
        let g = fit.response(w);
        let _ = writeln!(
            out,
            "{:?},{:?},{:?}",
            w / (2.0 * std::f64::consts::PI),
            g.norm(),
            g.arg().to_degrees()
        );
    }
    out
}

fn log_spaced(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1).max(1) as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits() {
        assert_eq!(sig(5.1), "5.10000");
        assert_eq!(sig(0.0167), "0.0167000");
        assert_eq!(sig(2.2e6), "2.20000e6");
        assert_eq!(sig(-14.2), "-14.2000");
    }

    /// Any element name, quoted where TOML needs it, reads back as itself;
    /// a value its rule refuses is not written.
    #[test]
    fn override_reads_back_for_any_element_name() {
        let param = |value: f64| ParamReport {
            value,
            ci95: None,
            std_error: None,
            unit: "N".to_string(),
        };
        let (good, bad) = (param(5.1), param(-1.0));
        for element in ["bearing_friction", "bearing rl", "a\"b", "x.y", "ü"] {
            let mut out = String::new();
            write_override(&mut out, element, &[("f_c", &good), ("f_s", &bad)], &[]);
            let table: toml::Table = out.parse().expect("valid TOML");
            let values = &table["overrides"][element];
            assert_eq!(values["f_c"].as_float(), Some(5.1), "{out}");
            assert!(values.get("f_s").is_none(), "{out}");
        }
    }
}
