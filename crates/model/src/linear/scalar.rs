//! The scalar types the physics is written over: `f64` for simulation and
//! forward-mode dual numbers ([`Dual64`], and [`DualSVec64`] for several
//! directions at once) for exact Jacobians and sensitivities. One generic
//! implementation serves both, so the linearisation differentiates exactly the
//! code that is simulated.

use std::cmp::Ordering;

use nalgebra::RealField;
pub use num_dual::{Dual64, DualSVec64};

/// A real scalar: `f64` or a dual number carrying one directional derivative.
pub trait Scalar: RealField + Copy {
    /// The real part.
    fn value(self) -> f64;
    /// A constant (zero derivative).
    fn constant(value: f64) -> Self;
    /// Zero with zero derivative: a term that may be skipped without
    /// changing the value or the derivative. (Comparisons of dual numbers
    /// read the real part only, so `x == 0` is not this.)
    fn is_exactly_zero(self) -> bool;
    /// The value compared with `other` (the real part, for dual numbers):
    /// how the physics branches on a value, so that a compiled evaluation
    /// can check the same branch is taken.
    fn compare_value(self, other: f64) -> Option<Ordering> {
        self.value().partial_cmp(&other)
    }
    /// |v|, with derivative 0 at v = 0 (the middle of its subdifferential).
    /// The LuGre bristle law has this kink at zero sliding velocity;
    /// linearising a stuck contact uses the zero slope, as the paper's
    /// sticking Jacobians do.
    fn kink_abs(self) -> Self {
        if self.value() == 0.0 {
            Self::zero()
        } else {
            self.abs()
        }
    }
}

impl Scalar for f64 {
    #[inline]
    fn value(self) -> f64 {
        self
    }
    #[inline]
    fn constant(value: f64) -> Self {
        value
    }
    #[inline]
    fn is_exactly_zero(self) -> bool {
        self == 0.0
    }
    /// |v| (at zero both are +0).
    #[inline]
    fn kink_abs(self) -> Self {
        self.abs()
    }
}

impl Scalar for Dual64 {
    #[inline]
    fn value(self) -> f64 {
        self.re
    }
    #[inline]
    fn constant(value: f64) -> Self {
        Dual64::from_re(value)
    }
    #[inline]
    fn is_exactly_zero(self) -> bool {
        self.re == 0.0 && self.eps == 0.0
    }
}

/// A dual number carrying `N` directional derivatives at once (one pass
/// through the law for all of them: the record fit's sensitivities).
impl<const N: usize> Scalar for DualSVec64<N> {
    #[inline]
    fn value(self) -> f64 {
        self.re
    }
    #[inline]
    fn constant(value: f64) -> Self {
        DualSVec64::from_re(value)
    }
    #[inline]
    fn is_exactly_zero(self) -> bool {
        self.re == 0.0 && self.eps.0.is_none_or(|e| e.iter().all(|&d| d == 0.0))
    }
}

/// |v| with derivative 0 at v = 0 ([`Scalar::kink_abs`]).
#[inline]
pub fn kink_abs<S: Scalar>(v: S) -> S {
    v.kink_abs()
}
