//! How the bench measures: CPU time of the calling thread, medians of
//! repeated runs.

use std::time::Instant;

/// CPU time of the calling thread, s.
pub(crate) fn thread_cpu_time() -> f64 {
    cpu_time(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU time of the whole process (every thread), s.
pub(crate) fn process_cpu_time() -> f64 {
    cpu_time(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// The reading of a CPU-time clock, s (NaN if the clock cannot be read).
fn cpu_time(clock: libc::clockid_t) -> f64 {
    let mut spec = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own; the clock id is a constant.
    let status = unsafe { libc::clock_gettime(clock, &mut spec) };
    if status == 0 {
        spec.tv_sec as f64 + spec.tv_nsec as f64 * 1e-9
    } else {
        f64::NAN
    }
}

/// The median of `values` (sorted in place).
pub(crate) fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Median time of `repeat` calls, after one warm-up call.
pub(crate) fn median_time(
    repeat: usize,
    mut f: impl FnMut() -> anyhow::Result<()>,
) -> anyhow::Result<f64> {
    f()?;
    let mut times = Vec::with_capacity(repeat);
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        f()?;
        times.push(start.elapsed().as_secs_f64());
    }
    Ok(median(&mut times))
}
