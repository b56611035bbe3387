//! [`Traced`]: a [`Scalar`] that records what is computed with it. Running
//! the model's generic evaluation on traced values (inside
//! [`super::tape::record`]) yields the tape of its floating-point operations,
//! with every decision that structure made (which elements exist, which
//! evaluation path, which compensator) already taken, and every comparison
//! of values kept as a guard. Each traced value also carries the number the
//! evaluation computes at the recording's state, so comparisons can be
//! answered (and guarded) while recording.
//!
//! Every operation mirrors the `f64` implementation of the traits the
//! physics is written against (nalgebra's `RealField`, num-traits'
//! `Signed`): a compiled tape performs the operations the `f64` evaluation
//! performs, in the same order. What a compiled function cannot repeat (a
//! value read out as a plain number, an approximate comparison, a fused
//! multiply-add) marks the recording unusable, and the model is then
//! evaluated as before.

use std::cmp::Ordering;
use std::fmt;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

use nalgebra::{ComplexField, Field, RealField, SimdValue};
use num_traits::{FromPrimitive, Num, One, Signed, Zero};
use simba::scalar::SubsetOf;

use super::calls::{Call1, Call2};
use super::tape::{self, Holds, Node, NodeId, Slot};
use fistage_model::Scalar;

/// A real number that records the operations done with it.
#[derive(Clone, Copy)]
pub struct Traced {
    node: NodeId,
    value: f64,
}

impl Traced {
    /// An input of the compiled function, `value` at the recording's state.
    pub(crate) fn input(slot: Slot, value: f64) -> Self {
        Self {
            node: tape::push(Node::Input(slot), value),
            value,
        }
    }

    /// The node it is on the tape.
    pub(crate) fn node(self) -> NodeId {
        self.node
    }

    fn of(node: Node, value: f64) -> Self {
        Self {
            node: tape::push(node, value),
            value,
        }
    }

    fn call1(self, f: Call1) -> Self {
        Self::of(Node::Call1(f, self.node), f.apply(self.value))
    }

    fn call2(self, f: Call2, other: Self) -> Self {
        Self::of(
            Node::Call2(f, self.node, other.node),
            f.apply(self.value, other.value),
        )
    }

    /// The outcome of comparing with `other`, kept as a guard.
    fn compare(self, other: Self) -> Option<Ordering> {
        tape::guard(
            self.node,
            other.node,
            Holds::ordering(self.value, other.value),
        );
        self.value.partial_cmp(&other.value)
    }

    /// Marks the recording unusable: `what` cannot be compiled.
    fn unsupported(what: &'static str) {
        tape::mark_unusable(|| format!("the evaluation uses {what}, which is not compiled"));
    }
}

impl Scalar for Traced {
    #[track_caller]
    fn value(self) -> f64 {
        let at = std::panic::Location::caller();
        tape::mark_unusable(|| format!("the evaluation reads a value as a number at {at}"));
        self.value
    }

    fn constant(value: f64) -> Self {
        Self::of(Node::Const(value), value)
    }

    fn is_exactly_zero(self) -> bool {
        let zero = Self::constant(0.0);
        zero.node == self.node
    }

    fn compare_value(self, other: f64) -> Option<Ordering> {
        self.compare(Self::constant(other))
    }

    fn kink_abs(self) -> Self {
        self.abs()
    }
}

impl fmt::Debug for Traced {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Traced(#{}: {})", self.node, self.value)
    }
}

impl fmt::Display for Traced {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.value, f)
    }
}

impl PartialEq for Traced {
    fn eq(&self, other: &Self) -> bool {
        let equal = self.value == other.value;
        let holds = if equal { Holds::Equal } else { Holds::NotEqual };
        tape::guard(self.node, other.node, holds);
        equal
    }
}

impl PartialOrd for Traced {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        self.compare(*other)
    }
}

macro_rules! binary_op {
    ($trait:ident, $method:ident, $assign_trait:ident, $assign:ident, $node:ident, $op:tt) => {
        impl $trait for Traced {
            type Output = Self;
            #[inline]
            fn $method(self, other: Self) -> Self {
                Self::of(Node::$node(self.node, other.node), self.value $op other.value)
            }
        }
        impl $assign_trait for Traced {
            #[inline]
            fn $assign(&mut self, other: Self) {
                *self = *self $op other;
            }
        }
    };
}

binary_op!(Add, add, AddAssign, add_assign, Add, +);
binary_op!(Sub, sub, SubAssign, sub_assign, Sub, -);
binary_op!(Mul, mul, MulAssign, mul_assign, Mul, *);
binary_op!(Div, div, DivAssign, div_assign, Div, /);

impl Rem for Traced {
    type Output = Self;
    fn rem(self, other: Self) -> Self {
        self.call2(Call2::Rem, other)
    }
}

impl RemAssign for Traced {
    fn rem_assign(&mut self, other: Self) {
        *self = *self % other;
    }
}

impl Neg for Traced {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::of(Node::Neg(self.node), -self.value)
    }
}

impl Zero for Traced {
    fn zero() -> Self {
        Self::constant(0.0)
    }
    fn is_zero(&self) -> bool {
        *self == Self::zero()
    }
}

impl One for Traced {
    fn one() -> Self {
        Self::constant(1.0)
    }
}

impl Num for Traced {
    type FromStrRadixErr = <f64 as Num>::FromStrRadixErr;
    fn from_str_radix(text: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        f64::from_str_radix(text, radix).map(Self::constant)
    }
}

impl FromPrimitive for Traced {
    fn from_i64(n: i64) -> Option<Self> {
        Some(Self::constant(n as f64))
    }
    fn from_u64(n: u64) -> Option<Self> {
        Some(Self::constant(n as f64))
    }
    fn from_f64(n: f64) -> Option<Self> {
        Some(Self::constant(n))
    }
    fn from_f32(n: f32) -> Option<Self> {
        Some(Self::constant(n as f64))
    }
}

impl Signed for Traced {
    fn abs(&self) -> Self {
        Self::of(Node::Abs(self.node), self.value.abs())
    }
    fn abs_sub(&self, other: &Self) -> Self {
        if *self <= *other {
            Self::zero()
        } else {
            *self - *other
        }
    }
    fn signum(&self) -> Self {
        self.call1(Call1::Signum)
    }
    fn is_positive(&self) -> bool {
        Self::unsupported("a sign test (is_positive)");
        Signed::is_positive(&self.value)
    }
    fn is_negative(&self) -> bool {
        Self::unsupported("a sign test (is_negative)");
        Signed::is_negative(&self.value)
    }
}

impl approx::AbsDiffEq for Traced {
    type Epsilon = Self;
    fn default_epsilon() -> Self {
        Self::constant(f64::default_epsilon())
    }
    fn abs_diff_eq(&self, other: &Self, epsilon: Self) -> bool {
        Self::unsupported("an approximate comparison");
        self.value.abs_diff_eq(&other.value, epsilon.value)
    }
}

impl approx::RelativeEq for Traced {
    fn default_max_relative() -> Self {
        Self::constant(f64::default_max_relative())
    }
    fn relative_eq(&self, other: &Self, epsilon: Self, max_relative: Self) -> bool {
        Self::unsupported("an approximate comparison");
        self.value
            .relative_eq(&other.value, epsilon.value, max_relative.value)
    }
}

impl approx::UlpsEq for Traced {
    fn default_max_ulps() -> u32 {
        f64::default_max_ulps()
    }
    fn ulps_eq(&self, other: &Self, epsilon: Self, max_ulps: u32) -> bool {
        Self::unsupported("an approximate comparison");
        self.value.ulps_eq(&other.value, epsilon.value, max_ulps)
    }
}

impl SimdValue for Traced {
    const LANES: usize = 1;
    type Element = Self;
    type SimdBool = bool;

    fn splat(val: Self) -> Self {
        val
    }
    fn extract(&self, _: usize) -> Self {
        *self
    }
    unsafe fn extract_unchecked(&self, _: usize) -> Self {
        *self
    }
    fn replace(&mut self, _: usize, val: Self) {
        *self = val;
    }
    unsafe fn replace_unchecked(&mut self, _: usize, val: Self) {
        *self = val;
    }
    fn select(self, cond: bool, other: Self) -> Self {
        if cond { self } else { other }
    }
}

impl Field for Traced {}

impl SubsetOf<Traced> for Traced {
    fn to_superset(&self) -> Traced {
        *self
    }
    fn from_superset_unchecked(element: &Traced) -> Self {
        *element
    }
    fn is_in_subset(_: &Traced) -> bool {
        true
    }
}

impl SubsetOf<Traced> for f64 {
    fn to_superset(&self) -> Traced {
        Traced::constant(*self)
    }
    fn from_superset_unchecked(element: &Traced) -> f64 {
        element.value()
    }
    fn is_in_subset(_: &Traced) -> bool {
        true
    }
}

impl SubsetOf<Traced> for f32 {
    fn to_superset(&self) -> Traced {
        Traced::constant(*self as f64)
    }
    fn from_superset_unchecked(element: &Traced) -> f32 {
        element.value() as f32
    }
    fn is_in_subset(_: &Traced) -> bool {
        true
    }
}

impl ComplexField for Traced {
    type RealField = Self;

    fn from_real(re: Self) -> Self {
        re
    }
    fn real(self) -> Self {
        self
    }
    fn imaginary(self) -> Self {
        Self::zero()
    }
    fn modulus(self) -> Self {
        Signed::abs(&self)
    }
    fn modulus_squared(self) -> Self {
        self * self
    }
    fn argument(self) -> Self {
        if self >= Self::zero() {
            Self::zero()
        } else {
            Self::pi()
        }
    }
    fn norm1(self) -> Self {
        Signed::abs(&self)
    }
    fn scale(self, factor: Self) -> Self {
        self * factor
    }
    fn unscale(self, factor: Self) -> Self {
        self / factor
    }
    fn floor(self) -> Self {
        self.call1(Call1::Floor)
    }
    fn ceil(self) -> Self {
        self.call1(Call1::Ceil)
    }
    fn round(self) -> Self {
        self.call1(Call1::Round)
    }
    fn trunc(self) -> Self {
        self.call1(Call1::Trunc)
    }
    fn fract(self) -> Self {
        self.call1(Call1::Fract)
    }
    fn mul_add(self, a: Self, b: Self) -> Self {
        Self::unsupported("a fused multiply-add");
        Self::constant(self.value.mul_add(a.value, b.value))
    }
    fn abs(self) -> Self {
        Signed::abs(&self)
    }
    fn hypot(self, other: Self) -> Self {
        self.call2(Call2::Hypot, other)
    }
    fn recip(self) -> Self {
        Self::one() / self
    }
    fn conjugate(self) -> Self {
        self
    }
    fn sin(self) -> Self {
        self.call1(Call1::Sin)
    }
    fn cos(self) -> Self {
        self.call1(Call1::Cos)
    }
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    fn tan(self) -> Self {
        self.call1(Call1::Tan)
    }
    fn asin(self) -> Self {
        self.call1(Call1::Asin)
    }
    fn acos(self) -> Self {
        self.call1(Call1::Acos)
    }
    fn atan(self) -> Self {
        self.call1(Call1::Atan)
    }
    fn sinh(self) -> Self {
        self.call1(Call1::Sinh)
    }
    fn cosh(self) -> Self {
        self.call1(Call1::Cosh)
    }
    fn tanh(self) -> Self {
        self.call1(Call1::Tanh)
    }
    fn asinh(self) -> Self {
        self.call1(Call1::Asinh)
    }
    fn acosh(self) -> Self {
        self.call1(Call1::Acosh)
    }
    fn atanh(self) -> Self {
        self.call1(Call1::Atanh)
    }
    fn log(self, base: Self) -> Self {
        self.call2(Call2::Log, base)
    }
    fn log2(self) -> Self {
        self.call1(Call1::Log2)
    }
    fn log10(self) -> Self {
        self.call1(Call1::Log10)
    }
    fn ln(self) -> Self {
        self.call1(Call1::Ln)
    }
    fn ln_1p(self) -> Self {
        self.call1(Call1::Ln1p)
    }
    fn sqrt(self) -> Self {
        Self::of(Node::Sqrt(self.node), self.value.sqrt())
    }
    fn exp(self) -> Self {
        self.call1(Call1::Exp)
    }
    fn exp2(self) -> Self {
        self.call1(Call1::Exp2)
    }
    fn exp_m1(self) -> Self {
        self.call1(Call1::ExpM1)
    }
    fn powi(self, n: i32) -> Self {
        self.call1(Call1::Powi(n))
    }
    fn powf(self, n: Self) -> Self {
        self.call2(Call2::Powf, n)
    }
    fn powc(self, n: Self) -> Self {
        self.call2(Call2::Powf, n)
    }
    fn cbrt(self) -> Self {
        self.call1(Call1::Cbrt)
    }
    fn is_finite(&self) -> bool {
        Self::unsupported("a finiteness test");
        self.value.is_finite()
    }
    fn try_sqrt(self) -> Option<Self> {
        (self >= Self::zero()).then(|| self.sqrt())
    }
}

impl RealField for Traced {
    fn is_sign_positive(&self) -> bool {
        Self::unsupported("a sign test (is_sign_positive)");
        self.value.is_sign_positive()
    }
    fn is_sign_negative(&self) -> bool {
        Self::unsupported("a sign test (is_sign_negative)");
        self.value.is_sign_negative()
    }
    fn copysign(self, sign: Self) -> Self {
        self.call2(Call2::Copysign, sign)
    }
    fn max(self, other: Self) -> Self {
        self.call2(Call2::Max, other)
    }
    fn min(self, other: Self) -> Self {
        self.call2(Call2::Min, other)
    }
    fn clamp(self, min: Self, max: Self) -> Self {
        Self::unsupported("a clamp");
        Self::constant(RealField::clamp(self.value, min.value, max.value))
    }
    fn atan2(self, other: Self) -> Self {
        self.call2(Call2::Atan2, other)
    }
    fn min_value() -> Option<Self> {
        Some(Self::constant(f64::MIN))
    }
    fn max_value() -> Option<Self> {
        Some(Self::constant(f64::MAX))
    }
    fn pi() -> Self {
        Self::constant(std::f64::consts::PI)
    }
    fn two_pi() -> Self {
        Self::constant(std::f64::consts::TAU)
    }
    fn frac_pi_2() -> Self {
        Self::constant(std::f64::consts::FRAC_PI_2)
    }
    fn frac_pi_3() -> Self {
        Self::constant(std::f64::consts::FRAC_PI_3)
    }
    fn frac_pi_4() -> Self {
        Self::constant(std::f64::consts::FRAC_PI_4)
    }
    fn frac_pi_6() -> Self {
        Self::constant(std::f64::consts::FRAC_PI_6)
    }
    fn frac_pi_8() -> Self {
        Self::constant(std::f64::consts::FRAC_PI_8)
    }
    fn frac_1_pi() -> Self {
        Self::constant(std::f64::consts::FRAC_1_PI)
    }
    fn frac_2_pi() -> Self {
        Self::constant(std::f64::consts::FRAC_2_PI)
    }
    fn frac_2_sqrt_pi() -> Self {
        Self::constant(std::f64::consts::FRAC_2_SQRT_PI)
    }
    fn e() -> Self {
        Self::constant(std::f64::consts::E)
    }
    fn log2_e() -> Self {
        Self::constant(std::f64::consts::LOG2_E)
    }
    fn log10_e() -> Self {
        Self::constant(std::f64::consts::LOG10_E)
    }
    fn ln_2() -> Self {
        Self::constant(std::f64::consts::LN_2)
    }
    fn ln_10() -> Self {
        Self::constant(std::f64::consts::LN_10)
    }
}
