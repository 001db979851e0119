//! The operations of twv-ir/1 and their semantics, as in CasADi's generated C (double precision).
//!
//! This is the interpreter's definition of each operation. The emitter (twv-emit) writes the
//! same expression as Rust source; the generated-vs-interpreted tests check, bit for bit, that the
//! two agree. C-library functions Rust's `std` does not route to the C library (`erf`, which is
//! unstable, and `asinh`/`acosh`/`atanh`, which `std` implements itself) are called from libm so
//! that results match CasADi's C.

macro_rules! op_enum {
    ($(#[$meta:meta])* $name:ident { $($variant:ident = $text:literal),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name { $($variant),* }

        impl $name {
            /// Every operation of this arity, in declaration order.
            pub const ALL: &'static [$name] = &[$($name::$variant),*];

            /// The operation's IR name.
            pub fn name(self) -> &'static str {
                match self { $($name::$variant => $text),* }
            }

            /// The operation with this IR name, if it has this arity.
            pub fn from_name(name: &str) -> Option<Self> {
                match name { $($text => Some($name::$variant),)* _ => None }
            }
        }
    };
}

op_enum!(
    /// Operations of one operand.
    UnaryOp {
        Neg = "neg", Exp = "exp", Log = "log", Sqrt = "sqrt", Sq = "sq", Twice = "twice",
        Sin = "sin", Cos = "cos", Tan = "tan", Asin = "asin", Acos = "acos", Atan = "atan",
        Fabs = "fabs", Sign = "sign", Inv = "inv", Sinh = "sinh", Cosh = "cosh", Tanh = "tanh",
        Asinh = "asinh", Acosh = "acosh", Atanh = "atanh", Floor = "floor", Ceil = "ceil",
        Erf = "erf", Not = "not", Log1p = "log1p", Expm1 = "expm1",
    }
);

op_enum!(
    /// Operations of two operands.
    BinaryOp {
        Add = "add", Sub = "sub", Mul = "mul", Div = "div", Pow = "pow", Constpow = "constpow",
        Fmin = "fmin", Fmax = "fmax", Atan2 = "atan2", Copysign = "copysign", Fmod = "fmod",
        Lt = "lt", Le = "le", Eq = "eq", Ne = "ne", And = "and", Or = "or",
        IfElseZero = "if_else_zero", Hypot = "hypot",
    }
);

/// C library functions that `std` does not call (see the module comment).
pub mod libm {
    unsafe extern "C" {
        fn erf(x: f64) -> f64;
        fn asinh(x: f64) -> f64;
        fn acosh(x: f64) -> f64;
        fn atanh(x: f64) -> f64;
    }
    /// C `erf`.
    pub fn c_erf(x: f64) -> f64 {
        // SAFETY: a pure C library function of one double, defined for every input.
        unsafe { erf(x) }
    }
    /// C `asinh`.
    pub fn c_asinh(x: f64) -> f64 {
        // SAFETY: as above.
        unsafe { asinh(x) }
    }
    /// C `acosh`.
    pub fn c_acosh(x: f64) -> f64 {
        // SAFETY: as above.
        unsafe { acosh(x) }
    }
    /// C `atanh`.
    pub fn c_atanh(x: f64) -> f64 {
        // SAFETY: as above.
        unsafe { atanh(x) }
    }
}

/// 1.0 for true, 0.0 for false: C's conversion of a comparison to double.
fn truth(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

impl UnaryOp {
    /// The value of the operation at `a`.
    pub fn apply(self, a: f64) -> f64 {
        match self {
            UnaryOp::Neg => -a,
            UnaryOp::Exp => a.exp(),
            UnaryOp::Log => a.ln(),
            UnaryOp::Sqrt => a.sqrt(),
            UnaryOp::Sq => a * a,
            UnaryOp::Twice => 2.0 * a,
            UnaryOp::Sin => twv_kernels::trig::sin_cos(a).0,
            UnaryOp::Cos => twv_kernels::trig::sin_cos(a).1,
            UnaryOp::Tan => a.tan(),
            UnaryOp::Asin => a.asin(),
            UnaryOp::Acos => a.acos(),
            UnaryOp::Atan => a.atan(),
            UnaryOp::Fabs => a.abs(),
            // CasADi: x<0 ? -1 : x>0 ? 1 : x (keeps 0, -0 and NaN).
            UnaryOp::Sign => {
                if a < 0.0 {
                    -1.0
                } else if a > 0.0 {
                    1.0
                } else {
                    a
                }
            }
            UnaryOp::Inv => 1.0 / a,
            UnaryOp::Sinh => a.sinh(),
            UnaryOp::Cosh => a.cosh(),
            UnaryOp::Tanh => a.tanh(),
            UnaryOp::Asinh => libm::c_asinh(a),
            UnaryOp::Acosh => libm::c_acosh(a),
            UnaryOp::Atanh => libm::c_atanh(a),
            UnaryOp::Floor => a.floor(),
            UnaryOp::Ceil => a.ceil(),
            UnaryOp::Erf => libm::c_erf(a),
            UnaryOp::Not => truth(a == 0.0),
            UnaryOp::Log1p => a.ln_1p(),
            UnaryOp::Expm1 => a.exp_m1(),
        }
    }
}

impl BinaryOp {
    /// The value of the operation at `(a, b)`.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            BinaryOp::Add => a + b,
            BinaryOp::Sub => a - b,
            BinaryOp::Mul => a * b,
            BinaryOp::Div => a / b,
            BinaryOp::Pow | BinaryOp::Constpow => a.powf(b),
            BinaryOp::Fmin => a.min(b),
            BinaryOp::Fmax => a.max(b),
            BinaryOp::Atan2 => a.atan2(b),
            BinaryOp::Copysign => a.copysign(b),
            BinaryOp::Fmod => a % b,
            BinaryOp::Lt => truth(a < b),
            BinaryOp::Le => truth(a <= b),
            BinaryOp::Eq => truth(a == b),
            BinaryOp::Ne => truth(a != b),
            BinaryOp::And => truth(a != 0.0 && b != 0.0),
            BinaryOp::Or => truth(a != 0.0 || b != 0.0),
            BinaryOp::IfElseZero => {
                if a != 0.0 {
                    b
                } else {
                    0.0
                }
            }
            BinaryOp::Hypot => a.hypot(b),
        }
    }
}
