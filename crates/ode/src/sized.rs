//! Arithmetic over a state vector whose length the compiler knows: the
//! embedded pairs take a copy of their trial step for each state count up to
//! 8 (loops unrolled, no bounds checks) and one for any length; the
//! operations are the same.

/// State-count marker for "known only at run time".
pub(crate) const DYNAMIC: usize = 0;

/// The number of states: `N`, or `n` when `N` is [`DYNAMIC`]. With a
/// constant `N` every slice has a length the compiler knows.
#[inline(always)]
pub(crate) fn state_count<const N: usize>(n: usize) -> usize {
    if N == DYNAMIC { n } else { N }
}

/// `integrator.method::<N, _>(arguments)` with `N` the state count `n` when
/// it is 1 to 8, else [`DYNAMIC`].
macro_rules! with_state_count {
    ($n:expr, $integrator:ident . $method:ident ( $($argument:expr),* )) => {
        match $n {
            1 => $integrator.$method::<1, _>($($argument),*),
            2 => $integrator.$method::<2, _>($($argument),*),
            3 => $integrator.$method::<3, _>($($argument),*),
            4 => $integrator.$method::<4, _>($($argument),*),
            5 => $integrator.$method::<5, _>($($argument),*),
            6 => $integrator.$method::<6, _>($($argument),*),
            7 => $integrator.$method::<7, _>($($argument),*),
            8 => $integrator.$method::<8, _>($($argument),*),
            _ => $integrator.$method::<{ $crate::sized::DYNAMIC }, _>($($argument),*),
        }
    };
}
pub(crate) use with_state_count;
