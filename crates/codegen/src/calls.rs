//! The library functions a traced evaluation may call (exponential, sine,
//! arctangent, ...). Compiled code calls each through a C-ABI function that
//! applies the very `f64` method the evaluation applies, so a compiled
//! function gives the same numbers as the evaluation it was traced from.

/// A function of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Call1 {
    Exp,
    Exp2,
    ExpM1,
    Ln,
    Ln1p,
    Log2,
    Log10,
    Cbrt,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    Floor,
    Ceil,
    Round,
    Trunc,
    Fract,
    Signum,
    /// `x.powi(n)`.
    Powi(i32),
}

/// A function of two arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Call2 {
    Atan2,
    Powf,
    Hypot,
    Log,
    Copysign,
    Max,
    Min,
    Rem,
}

macro_rules! unary {
    ($($variant:ident => $name:ident: $f:expr;)*) => {
        $(
            extern "C" fn $name(x: f64) -> f64 {
                let f: fn(f64) -> f64 = $f;
                f(x)
            }
        )*
        impl Call1 {
            /// The function applied to `x`.
            pub(crate) fn apply(self, x: f64) -> f64 {
                match self {
                    $(Self::$variant => $name(x),)*
                    Self::Powi(n) => x.powi(n),
                }
            }

            /// Symbol name and address of the C-ABI function compiled code calls.
            pub(crate) fn symbol(self) -> (&'static str, *const u8) {
                match self {
                    $(Self::$variant => (stringify!($name), $name as *const u8),)*
                    Self::Powi(_) => ("fistage_powi", powi as *const u8),
                }
            }

            /// Every function (`Powi` stands for all exponents).
            pub(crate) const ALL: &[Self] = &[$(Self::$variant,)* Self::Powi(0)];

            /// A number that tells functions apart (with the exponent of `Powi`).
            pub(crate) fn code(self) -> u32 {
                match self {
                    Self::Powi(n) => (1 << 16) ^ (n as u32),
                    other => Self::ALL.iter().position(|f| *f == other).unwrap_or(0) as u32,
                }
            }
        }
    };
}

unary! {
    Exp => fistage_exp: f64::exp;
    Exp2 => fistage_exp2: f64::exp2;
    ExpM1 => fistage_exp_m1: f64::exp_m1;
    Ln => fistage_ln: f64::ln;
    Ln1p => fistage_ln_1p: f64::ln_1p;
    Log2 => fistage_log2: f64::log2;
    Log10 => fistage_log10: f64::log10;
    Cbrt => fistage_cbrt: f64::cbrt;
    Sin => fistage_sin: f64::sin;
    Cos => fistage_cos: f64::cos;
    Tan => fistage_tan: f64::tan;
    Asin => fistage_asin: f64::asin;
    Acos => fistage_acos: f64::acos;
    Atan => fistage_atan: f64::atan;
    Sinh => fistage_sinh: f64::sinh;
    Cosh => fistage_cosh: f64::cosh;
    Tanh => fistage_tanh: f64::tanh;
    Asinh => fistage_asinh: f64::asinh;
    Acosh => fistage_acosh: f64::acosh;
    Atanh => fistage_atanh: f64::atanh;
    Floor => fistage_floor: f64::floor;
    Ceil => fistage_ceil: f64::ceil;
    Round => fistage_round: f64::round;
    Trunc => fistage_trunc: f64::trunc;
    Fract => fistage_fract: f64::fract;
    Signum => fistage_signum: f64::signum;
}

/// `x.powi(n)`: the exponent travels as a double (it is an `i32` and
/// converts exactly both ways).
extern "C" fn powi(x: f64, n: f64) -> f64 {
    x.powi(n as i32)
}

macro_rules! binary {
    ($($variant:ident => $name:ident: $f:expr;)*) => {
        $(
            extern "C" fn $name(a: f64, b: f64) -> f64 {
                let f: fn(f64, f64) -> f64 = $f;
                f(a, b)
            }
        )*
        impl Call2 {
            /// The function applied to `a` and `b`.
            pub(crate) fn apply(self, a: f64, b: f64) -> f64 {
                match self {
                    $(Self::$variant => $name(a, b),)*
                }
            }

            /// Symbol name and address of the C-ABI function compiled code calls.
            pub(crate) fn symbol(self) -> (&'static str, *const u8) {
                match self {
                    $(Self::$variant => (stringify!($name), $name as *const u8),)*
                }
            }

            /// Every function.
            pub(crate) const ALL: &[Self] = &[$(Self::$variant,)*];

            /// A number that tells functions apart.
            pub(crate) fn code(self) -> u32 {
                Self::ALL.iter().position(|f| *f == self).unwrap_or(0) as u32
            }
        }
    };
}

binary! {
    Atan2 => fistage_atan2: f64::atan2;
    Powf => fistage_powf: f64::powf;
    Hypot => fistage_hypot: f64::hypot;
    Log => fistage_log: f64::log;
    Copysign => fistage_copysign: f64::copysign;
    Max => fistage_max: f64::max;
    Min => fistage_min: f64::min;
    Rem => fistage_rem: |a, b| a % b;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_function_has_its_own_code_and_symbol() {
        let mut codes: Vec<u32> = Call1::ALL.iter().map(|f| f.code()).collect();
        codes.extend(Call2::ALL.iter().map(|f| f.code() + 1000));
        codes.push(Call1::Powi(3).code());
        let count = codes.len();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), count);
        assert_eq!(Call1::Powi(3).apply(2.0), 8.0);
        assert_eq!(Call1::Exp.apply(0.5), 0.5f64.exp());
        assert_eq!(Call2::Atan2.apply(1.0, -2.0), 1.0f64.atan2(-2.0));
        let names: Vec<&str> = Call1::ALL.iter().map(|f| f.symbol().0).collect();
        assert!(names.iter().all(|n| n.starts_with("fistage_")));
    }
}
