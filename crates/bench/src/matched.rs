//! Matched accuracy for `fistage bench --peers`: what a peer pays to reach the
//! error fistage reached, from the rows of one invocation. A peer and fistage
//! at the same rtol rarely reach the same error (CVODE's error at a given
//! rtol is 30 to 100 times fistage's on the paper's stages), so the ratio at
//! the same rtol says little about the cost of an answer of a given quality.
//!
//! For each fistage row the peer's cost at that row's relative error is read
//! from the peer's own rows: interpolated linearly in log CPU time against
//! log error between the cheapest peer row that reaches the error and the most
//! accurate cheaper one that does not; an upper bound when no cheaper row
//! brackets it; "not reached" when no peer row gets there.

/// One row of a table: its tolerance, CPU time and relative error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AccuracyRow {
    pub rtol: f64,
    pub cpu_s: f64,
    pub relative: f64,
}

/// What a peer pays for a given relative error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum PeerCost {
    /// Between a row that misses the error and a costlier one that reaches it.
    Interpolated {
        cpu_s: f64,
        missing: AccuracyRow,
        reaching: AccuracyRow,
    },
    /// The cheapest row that reaches the error, with no cheaper row to
    /// bracket it: the peer may need less.
    AtMost { cpu_s: f64, reaching: AccuracyRow },
    /// No row reaches the error; the most accurate row.
    NotReached { best: AccuracyRow },
}

/// The cost of `target` relative error from a peer's rows.
pub(crate) fn peer_cost_at(target: f64, peer: &[AccuracyRow]) -> Option<PeerCost> {
    let finite = |row: &&AccuracyRow| row.relative.is_finite() && row.cpu_s > 0.0;
    let cheapest_reaching = peer
        .iter()
        .filter(finite)
        .filter(|row| row.relative <= target)
        .min_by(|a, b| a.cpu_s.total_cmp(&b.cpu_s));
    let Some(&reaching) = cheapest_reaching else {
        let best = peer
            .iter()
            .filter(finite)
            .min_by(|a, b| a.relative.total_cmp(&b.relative))?;
        return Some(PeerCost::NotReached { best: *best });
    };
    let cheaper_missing = peer
        .iter()
        .filter(finite)
        .filter(|row| row.relative > target && row.cpu_s < reaching.cpu_s)
        .min_by(|a, b| a.relative.total_cmp(&b.relative));
    Some(match cheaper_missing {
        Some(&missing) if reaching.relative > 0.0 => {
            let fraction = (target.ln() - missing.relative.ln())
                / (reaching.relative.ln() - missing.relative.ln());
            let ln_cpu = missing.cpu_s.ln() + fraction * (reaching.cpu_s.ln() - missing.cpu_s.ln());
            PeerCost::Interpolated {
                cpu_s: ln_cpu.exp(),
                missing,
                reaching,
            }
        }
        _ => PeerCost::AtMost {
            cpu_s: reaching.cpu_s,
            reaching,
        },
    })
}

/// The matched-accuracy table: every fistage row against every peer.
pub(crate) fn print_matched(fistage: &[AccuracyRow], peers: &[(String, Vec<AccuracyRow>)]) {
    if fistage.is_empty() || peers.is_empty() {
        return;
    }
    println!(
        "\nMatched accuracy: the CPU time each peer needs for the relative error of each fistage row, \
         from this invocation's rows (log-log interpolation between the peer's rows that bracket it; \
         \"at most\" where none cheaper brackets it):\n"
    );
    println!(
        "| fistage rtol | fistage relative error | fistage CPU ms | peer | peer CPU ms at that error | peer rows used (rtol) | peer CPU / fistage CPU |"
    );
    println!("|---|---|---|---|---|---|---|");
    for row in fistage {
        for (method, rows) in peers {
            let Some(cost) = peer_cost_at(row.relative, rows) else {
                continue;
            };
            let head = format!(
                "| {:.0e} | {:.2e} | {:.2} | {method} |",
                row.rtol,
                row.relative,
                row.cpu_s * 1e3
            );
            match cost {
                PeerCost::Interpolated {
                    cpu_s,
                    missing,
                    reaching,
                } => println!(
                    "{head} {:.2} | {:.0e} to {:.0e} | {:.1} |",
                    cpu_s * 1e3,
                    missing.rtol,
                    reaching.rtol,
                    cpu_s / row.cpu_s
                ),
                PeerCost::AtMost { cpu_s, reaching } => println!(
                    "{head} at most {:.2} | {:.0e} | at most {:.1} |",
                    cpu_s * 1e3,
                    reaching.rtol,
                    cpu_s / row.cpu_s
                ),
                PeerCost::NotReached { best } => println!(
                    "{head} not reached (best {:.2e} at rtol {:.0e}) | - | - |",
                    best.relative, best.rtol
                ),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(rtol: f64, cpu_ms: f64, relative: f64) -> AccuracyRow {
        AccuracyRow {
            rtol,
            cpu_s: cpu_ms * 1e-3,
            relative,
        }
    }

    #[test]
    fn a_power_law_peer_is_interpolated_exactly() {
        // cost = 10 ms * (1e-6 / error)^0.25: log-log linear, so the
        // interpolated cost at any bracketed error is the law's.
        let law = |e: f64| 10.0 * (1e-6_f64 / e).powf(0.25);
        let peer: Vec<_> = [1e-5, 1e-6, 1e-7, 1e-8]
            .iter()
            .map(|&e| row(e * 10.0, law(e), e))
            .collect();
        let target = 2.5e-7;
        let Some(PeerCost::Interpolated {
            cpu_s,
            missing,
            reaching,
        }) = peer_cost_at(target, &peer)
        else {
            panic!("not interpolated");
        };
        assert!((cpu_s * 1e3 - law(target)).abs() < 1e-9 * law(target));
        assert_eq!((missing.relative, reaching.relative), (1e-6, 1e-7));
    }

    #[test]
    fn a_row_meeting_the_error_exactly_costs_its_own_time() {
        let peer = [row(1e-8, 40.0, 5e-6), row(1e-10, 70.0, 2e-7)];
        let Some(PeerCost::Interpolated { cpu_s, .. }) = peer_cost_at(2e-7, &peer) else {
            panic!("not interpolated");
        };
        assert!((cpu_s - 0.070).abs() < 1e-12, "{cpu_s}");
    }

    #[test]
    fn bounds_and_misses_are_named() {
        // Every row more accurate than the target: only an upper bound.
        let accurate = [row(1e-8, 40.0, 1e-8), row(1e-10, 70.0, 1e-9)];
        assert_eq!(
            peer_cost_at(1e-7, &accurate),
            Some(PeerCost::AtMost {
                cpu_s: 0.040,
                reaching: accurate[0]
            })
        );
        // A less accurate row that costs more does not bracket.
        let slow_miss = [row(1e-6, 90.0, 1e-5), row(1e-8, 40.0, 1e-8)];
        assert!(matches!(
            peer_cost_at(1e-7, &slow_miss),
            Some(PeerCost::AtMost { .. })
        ));
        // No row gets there.
        let coarse = [row(1e-6, 10.0, 1e-4), row(1e-8, 40.0, 3e-6)];
        assert_eq!(
            peer_cost_at(1e-7, &coarse),
            Some(PeerCost::NotReached { best: coarse[1] })
        );
        assert_eq!(peer_cost_at(1e-7, &[]), None);
    }
}
