//! One closed-form expression of a hand model: a small tree over the model's own names, evaluated
//! with `f64` for values and with [`Dual`](crate::hand_model::scalar::Dual) for exact derivatives.

use crate::hand_model::scalar::Real;

/// Which of the model's arguments a name reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Var {
    /// State `x[i]`.
    X(usize),
    /// Input `u[i]`.
    U(usize),
    /// Parameter `p[i]`.
    P(usize),
}

/// The functions a hand file may call.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Sqrt,
    Exp,
    Log,
    /// An operation of the derived IR that hand files cannot write (e.g. `atan2`): kept by name
    /// for the symbolic difference, never evaluated.
    Other(String),
}

impl Func {
    /// The function a hand file names, if it is one.
    pub fn from_name(name: &str) -> Option<Func> {
        Some(match name {
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "sqrt" => Func::Sqrt,
            "exp" => Func::Exp,
            "log" | "ln" => Func::Log,
            _ => return None,
        })
    }

    /// Its name as printed.
    pub fn name(&self) -> &str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Sqrt => "sqrt",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Other(name) => name,
        }
    }
}

/// An expression tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Num(f64),
    /// π, kept as itself so that the simplifier knows `sin(pi - phi)` is `sin(phi)` exactly.
    Pi,
    Var(Var),
    Neg(Box<Expr>),
    Add(Box<Expr>, Box<Expr>),
    Sub(Box<Expr>, Box<Expr>),
    Mul(Box<Expr>, Box<Expr>),
    Div(Box<Expr>, Box<Expr>),
    Pow(Box<Expr>, Box<Expr>),
    Call(Func, Box<Expr>),
}

/// The values an expression reads.
pub struct Args<'a, S> {
    pub x: &'a [S],
    pub u: &'a [S],
    pub p: &'a [f64],
}

impl Expr {
    pub fn sum(a: Expr, b: Expr) -> Expr {
        Expr::Add(Box::new(a), Box::new(b))
    }
    pub fn product(a: Expr, b: Expr) -> Expr {
        Expr::Mul(Box::new(a), Box::new(b))
    }

    /// The operands of an operation (none for a number or a name).
    pub fn children(&self) -> [Option<&Expr>; 2] {
        match self {
            Expr::Num(_) | Expr::Pi | Expr::Var(_) => [None, None],
            Expr::Neg(a) | Expr::Call(_, a) => [Some(a), None],
            Expr::Add(a, b)
            | Expr::Sub(a, b)
            | Expr::Mul(a, b)
            | Expr::Div(a, b)
            | Expr::Pow(a, b) => [Some(a), Some(b)],
        }
    }

    /// The exponent as a small integer, when it is a constant one (`x^2`, `x^-1`, `x^(3^2)`).
    pub fn small_integer(&self) -> Option<i32> {
        let v = self.constant()?;
        (v.fract() == 0.0 && v.abs() <= 64.0).then_some(v as i32)
    }

    /// The value of an expression of numbers only.
    fn constant(&self) -> Option<f64> {
        let args: Args<'_, f64> = Args {
            x: &[],
            u: &[],
            p: &[],
        };
        self.has_no_names().then(|| self.eval(&args))
    }

    fn has_no_names(&self) -> bool {
        match self {
            Expr::Num(_) | Expr::Pi => true,
            Expr::Var(_) | Expr::Call(Func::Other(_), _) => false,
            Expr::Neg(a) | Expr::Call(_, a) => a.has_no_names(),
            Expr::Add(a, b)
            | Expr::Sub(a, b)
            | Expr::Mul(a, b)
            | Expr::Div(a, b)
            | Expr::Pow(a, b) => a.has_no_names() && b.has_no_names(),
        }
    }

    /// The value (or dual number) at `args`.
    pub fn eval<S: Real>(&self, args: &Args<'_, S>) -> S {
        match self {
            Expr::Num(v) => S::cst(*v),
            Expr::Pi => S::cst(std::f64::consts::PI),
            Expr::Var(Var::X(i)) => args.x[*i],
            Expr::Var(Var::U(i)) => args.u[*i],
            Expr::Var(Var::P(i)) => S::cst(args.p[*i]),
            Expr::Neg(a) => -a.eval(args),
            Expr::Add(a, b) => a.eval(args) + b.eval(args),
            Expr::Sub(a, b) => a.eval(args) - b.eval(args),
            Expr::Mul(a, b) => a.eval(args) * b.eval(args),
            Expr::Div(a, b) => a.eval(args) / b.eval(args),
            Expr::Pow(a, b) => {
                let base = a.eval(args);
                match b.small_integer() {
                    Some(n) => powi(base, n),
                    None => (base.ln() * b.eval(args)).exp(),
                }
            }
            Expr::Call(f, a) => {
                let v = a.eval(args);
                match f {
                    Func::Sin => v.sin(),
                    Func::Cos => v.cos(),
                    Func::Tan => v.sin() / v.cos(),
                    Func::Sqrt => v.sqrt(),
                    Func::Exp => v.exp(),
                    Func::Log => v.ln(),
                    Func::Other(_) => S::cst(f64::NAN),
                }
            }
        }
    }
}

/// `base^n` by repeated multiplication (exact derivatives for duals, no log of a negative base).
fn powi<S: Real>(base: S, n: i32) -> S {
    let mut acc = S::cst(1.0);
    for _ in 0..n.unsigned_abs() {
        acc = acc * base;
    }
    if n < 0 {
        S::cst(1.0) / acc
    } else {
        acc
    }
}
