//! A canonical form of an expression, so that the difference between a hand entry and the
//! derived one can be printed as the term that is missing or wrong (`m2*b*sin(phi)*w_z^2`), not as
//! two long formulas.
//!
//! The form is a sum of monomials with `f64` coefficients over atoms: the model's names,
//! `sin(v)` and `cos(v)` of one name, and opaque parts (a square root, a division by a sum) kept
//! as printed text. Products are expanded, `sin`/`cos` of integer combinations of names are
//! expanded by the angle-sum rules, and every `sin(v)^2` is rewritten as `1 - cos(v)^2`, so two
//! polynomial expressions that are equal for all values have the same form, however grouped.
//! Expressions with a division by a sum (f after the mass-matrix solve) only cancel if both sides
//! divide by the same sum; that is why the audit prints differences of M, Cp, F and Q.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

use super::expr::{Expr, Func, Var};

/// Past this many terms an expression is not worth printing (and its expansion not worth the
/// time): the symbolic difference is skipped.
pub const MAX_TERMS: usize = 4000;

/// The longest text an opaque part may have (nested divisions by sums grow it quickly).
const MAX_OPAQUE: usize = 20_000;

/// A factor of a monomial, in the order a term prints: parameters, trigonometric factors,
/// other parts, then states and inputs (`m2*b*sin(phi)*w_z^2`).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum Atom {
    /// π: inside sin and cos its multiples of π/2 are exact; anywhere else it becomes its value
    /// when the form is finished (the derivation writes it as a number).
    Pi,
    Param(usize),
    Sin(Var),
    Cos(Var),
    /// A part that is not a polynomial in the other atoms, as printed text (self-delimited).
    Opaque(String),
    /// A state or an input.
    Signal(Var),
}

/// Factors with their (non-zero, possibly negative) exponents.
type Monomial = BTreeMap<Atom, i32>;

/// A sum of monomials with their coefficients (no zero coefficients).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Poly {
    terms: BTreeMap<Monomial, f64>,
}

/// An expansion that grew past [`MAX_TERMS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TooLarge;

/// The names the atoms print with.
pub struct Names<'a> {
    pub states: &'a [String],
    pub inputs: &'a [String],
    pub params: &'a [String],
}

impl Names<'_> {
    fn of(&self, v: Var) -> &str {
        match v {
            Var::X(i) => &self.states[i],
            Var::U(i) => &self.inputs[i],
            Var::P(i) => &self.params[i],
        }
    }
}

impl Poly {
    /// One of the model's names.
    pub(super) fn var(v: Var) -> Poly {
        let atom = match v {
            Var::P(i) => Atom::Param(i),
            signal => Atom::Signal(signal),
        };
        Poly::atom(atom, 1)
    }

    /// A part kept as text (self-delimited, e.g. `atan2(y, x)`).
    pub(super) fn opaque(text: String) -> Result<Poly, TooLarge> {
        if text.len() > MAX_OPAQUE {
            return Err(TooLarge);
        }
        Ok(Poly::atom(Atom::Opaque(text), 1))
    }

    /// The small integer this constant is (an exponent), if it is one.
    pub(super) fn small_integer(&self) -> Option<i32> {
        match self.as_monomial() {
            Some((m, c)) if m.is_empty() && c.fract() == 0.0 && c.abs() <= 64.0 => Some(c as i32),
            None if self.is_empty() => Some(0),
            _ => None,
        }
    }

    pub(super) fn constant(c: f64) -> Poly {
        let mut terms = BTreeMap::new();
        if c != 0.0 {
            terms.insert(Monomial::new(), c);
        }
        Poly { terms }
    }

    fn atom(a: Atom, exponent: i32) -> Poly {
        let mut m = Monomial::new();
        m.insert(a, exponent);
        let mut terms = BTreeMap::new();
        terms.insert(m, 1.0);
        Poly { terms }
    }

    /// Number of monomials.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// True for the zero polynomial.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The largest |coefficient| (the scale cancellation is judged against).
    pub fn scale(&self) -> f64 {
        self.terms.values().fold(0.0, |m, c| m.max(c.abs()))
    }

    fn add_term(&mut self, m: Monomial, c: f64) {
        match self.terms.entry(m) {
            Entry::Occupied(mut o) => {
                *o.get_mut() += c;
                if *o.get() == 0.0 {
                    o.remove();
                }
            }
            Entry::Vacant(v) => {
                if c != 0.0 {
                    v.insert(c);
                }
            }
        }
    }

    pub(super) fn plus(mut self, other: &Poly, sign: f64) -> Poly {
        for (m, c) in &other.terms {
            self.add_term(m.clone(), sign * c);
        }
        self
    }

    pub(super) fn times(&self, other: &Poly) -> Result<Poly, TooLarge> {
        if self.len() * other.len() > MAX_TERMS * 4 {
            return Err(TooLarge);
        }
        let mut out = Poly::default();
        for (ma, ca) in &self.terms {
            for (mb, cb) in &other.terms {
                let mut m = ma.clone();
                for (atom, e) in mb {
                    let entry = m.entry(atom.clone()).or_insert(0);
                    *entry += e;
                    if *entry == 0 {
                        m.remove(atom);
                    }
                }
                out.add_term(m, ca * cb);
            }
        }
        out.reduce_sin_squares()?;
        if out.len() > MAX_TERMS {
            return Err(TooLarge);
        }
        Ok(out)
    }

    /// `sin(v)^e` with e ≥ 2 becomes `sin(v)^(e-2) (1 - cos(v)^2)`, until no such factor is left:
    /// the unique representative modulo sin² + cos² = 1.
    fn reduce_sin_squares(&mut self) -> Result<(), TooLarge> {
        let sin_square = |m: &Monomial| {
            m.iter().find_map(|(a, e)| match a {
                Atom::Sin(v) if *e >= 2 => Some((*v, *e)),
                _ => None,
            })
        };
        let mut pending = Vec::new();
        self.terms.retain(|m, c| {
            let found = sin_square(m).is_some();
            if found {
                pending.push((m.clone(), *c));
            }
            !found
        });
        while let Some((mut m, c)) = pending.pop() {
            let Some((v, e)) = sin_square(&m) else {
                self.add_term(m, c);
                continue;
            };
            if e == 2 {
                m.remove(&Atom::Sin(v));
            } else {
                m.insert(Atom::Sin(v), e - 2);
            }
            let mut with_cos = m.clone();
            let cos = with_cos.entry(Atom::Cos(v)).or_insert(0);
            *cos += 2;
            if *cos == 0 {
                with_cos.remove(&Atom::Cos(v));
            }
            pending.push((m, c));
            pending.push((with_cos, -c));
            if pending.len() + self.len() > MAX_TERMS * 4 {
                return Err(TooLarge);
            }
        }
        Ok(())
    }

    /// The single monomial `c m` this is, if it is one.
    fn as_monomial(&self) -> Option<(&Monomial, f64)> {
        match self.terms.len() {
            1 => self.terms.iter().next().map(|(m, c)| (m, *c)),
            _ => None,
        }
    }

    /// `1 / self`: exact for a monomial, an opaque factor otherwise.
    pub(super) fn inverse(&self, names: &Names<'_>) -> Result<Poly, TooLarge> {
        Ok(match self.as_monomial() {
            Some((m, c)) => {
                let inv: Monomial = m.iter().map(|(a, e)| (a.clone(), -e)).collect();
                let mut terms = BTreeMap::new();
                terms.insert(inv, 1.0 / c);
                Poly { terms }
            }
            None => {
                let mut p = Poly::opaque(format!("({})", self.print(names)))?;
                p.terms = p
                    .terms
                    .into_iter()
                    .map(|(m, c)| (m.into_keys().map(|a| (a, -1)).collect(), c))
                    .collect();
                p
            }
        })
    }

    pub(super) fn power(&self, n: i32, names: &Names<'_>) -> Result<Poly, TooLarge> {
        let mut acc = Poly::constant(1.0);
        for _ in 0..n.unsigned_abs() {
            acc = acc.times(self)?;
        }
        if n < 0 {
            acc.inverse(names)
        } else {
            Ok(acc)
        }
    }

    /// The names with their integer multiples and the quarter turns this angle is a sum of
    /// (`2*phi - theta + pi/2` is ([phi: 2, theta: -1], 1)), if it is one.
    fn angle(&self) -> Option<(Vec<(Var, i32)>, i32)> {
        let small = |c: f64| c.fract() == 0.0 && c.abs() <= 12.0;
        let mut names = Vec::new();
        let mut quarters = 0;
        for (m, c) in &self.terms {
            let mut it = m.iter();
            match (it.next(), it.next()) {
                (Some((Atom::Signal(v), 1)), None) if small(*c) => names.push((*v, *c as i32)),
                (Some((Atom::Param(i), 1)), None) if small(*c) => {
                    names.push((Var::P(*i), *c as i32))
                }
                (Some((Atom::Pi, 1)), None) if small(2.0 * c) => quarters = (2.0 * c) as i32,
                _ => return None,
            }
        }
        Some((names, quarters))
    }

    /// π written as its value (`2*pi*m` is `6.283185307179586*m`), as the derivation has it.
    fn pi_as_number(self) -> Poly {
        let mut out = Poly::default();
        for (mut m, c) in self.terms {
            let c = match m.remove(&Atom::Pi) {
                Some(e) => c * std::f64::consts::PI.powi(e),
                None => c,
            };
            out.add_term(m, c);
        }
        out
    }

    /// Prints the form: terms in canonical order, negative exponents as a denominator.
    pub fn print(&self, names: &Names<'_>) -> String {
        if self.terms.is_empty() {
            return "0".into();
        }
        let mut out = String::new();
        for (k, (m, c)) in self.terms.iter().enumerate() {
            let (num, den): (Vec<_>, Vec<_>) = m.iter().partition(|(_, e)| **e > 0);
            let factor = |(a, e): &(&Atom, &i32)| {
                let text = match a {
                    Atom::Pi => "pi".to_string(),
                    Atom::Param(i) => names.of(Var::P(*i)).to_string(),
                    Atom::Signal(v) => names.of(*v).to_string(),
                    Atom::Sin(v) => format!("sin({})", names.of(*v)),
                    Atom::Cos(v) => format!("cos({})", names.of(*v)),
                    Atom::Opaque(s) => s.clone(),
                };
                match e.abs() {
                    1 => text,
                    n => format!("{text}^{n}"),
                }
            };
            let num: Vec<String> = num.iter().map(factor).collect();
            let den: Vec<String> = den.iter().map(factor).collect();
            let magnitude = c.abs();
            let mut term = if num.is_empty() || magnitude != 1.0 {
                let mut parts = vec![number(magnitude)];
                parts.extend(num);
                parts.join("*")
            } else {
                num.join("*")
            };
            match den.len() {
                0 => {}
                1 => term = format!("{term}/{}", den[0]),
                _ => term = format!("{term}/({})", den.join("*")),
            }
            let sign = if *c < 0.0 { "-" } else { "+" };
            if k == 0 {
                out.push_str(if *c < 0.0 { "-" } else { "" });
            } else {
                out.push_str(&format!(" {sign} "));
            }
            out.push_str(&term);
        }
        out
    }

    /// `self - other` with the coefficients that cancel to rounding (relative to the larger
    /// expression's scale) dropped.
    pub fn difference(&self, other: &Poly) -> Poly {
        let scale = self.scale().max(other.scale());
        let mut diff = self.clone().plus(other, -1.0);
        diff.terms.retain(|_, c| c.abs() > 1e-12 * scale);
        diff
    }
}

/// A coefficient as a person writes it: `2`, not `2.0`; shortest round-trip otherwise.
fn number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

/// The canonical form of `e`.
pub fn normal_form(e: &Expr, names: &Names<'_>) -> Result<Poly, TooLarge> {
    Ok(form(e, names)?.pi_as_number())
}

/// The canonical form of `e`, π still an atom.
fn form(e: &Expr, names: &Names<'_>) -> Result<Poly, TooLarge> {
    Ok(match e {
        Expr::Num(c) => Poly::constant(*c),
        Expr::Pi => Poly::atom(Atom::Pi, 1),
        Expr::Var(v) => Poly::var(*v),
        Expr::Neg(a) => Poly::default().plus(&form(a, names)?, -1.0),
        Expr::Add(a, b) => form(a, names)?.plus(&form(b, names)?, 1.0),
        Expr::Sub(a, b) => form(a, names)?.plus(&form(b, names)?, -1.0),
        Expr::Mul(a, b) => form(a, names)?.times(&form(b, names)?)?,
        Expr::Div(a, b) => form(a, names)?.times(&form(b, names)?.inverse(names)?)?,
        Expr::Pow(a, b) => match b.small_integer() {
            Some(n) => form(a, names)?.power(n, names)?,
            None => {
                let (base, exponent) = (form(a, names)?, form(b, names)?);
                let text = format!("({})^({})", base.print(names), exponent.print(names));
                Poly::opaque(text)?
            }
        },
        Expr::Call(f, a) => call(f, &form(a, names)?, names)?,
    })
}

pub(super) fn call(f: &Func, arg: &Poly, names: &Names<'_>) -> Result<Poly, TooLarge> {
    let trig = |sine: bool| -> Result<Option<Poly>, TooLarge> {
        let Some((combination, quarters)) = arg.angle() else {
            return Ok(None);
        };
        let units: i32 = combination.iter().map(|(_, k)| k.abs()).sum();
        if units > 12 {
            return Ok(None);
        }
        // sin and cos of a sum, one ±v at a time.
        let (mut s, mut c) = (Poly::default(), Poly::constant(1.0));
        for (v, k) in combination {
            let sign = f64::from(k.signum());
            let (sv, cv) = (
                Poly::default().plus(&Poly::atom(Atom::Sin(v), 1), sign),
                Poly::atom(Atom::Cos(v), 1),
            );
            for _ in 0..k.abs() {
                let next_s = s.times(&cv)?.plus(&c.times(&sv)?, 1.0);
                let next_c = c.times(&cv)?.plus(&s.times(&sv)?, -1.0);
                (s, c) = (next_s, next_c);
            }
        }
        // Then the quarter turns: sin(x + pi/2) = cos(x), cos(x + pi/2) = -sin(x).
        let negated = |p: Poly| Poly::default().plus(&p, -1.0);
        Ok(Some(match (sine, quarters.rem_euclid(4)) {
            (true, 0) | (false, 3) => s,
            (true, 1) | (false, 0) => c,
            (true, 2) | (false, 1) => negated(s),
            _ => negated(c),
        }))
    };
    let expanded = match f {
        Func::Sin => trig(true)?,
        Func::Cos => trig(false)?,
        Func::Tan => match (trig(true)?, trig(false)?) {
            (Some(s), Some(c)) => Some(s.times(&c.inverse(names)?)?),
            _ => None,
        },
        _ => None,
    };
    match expanded {
        Some(p) => Ok(p),
        None => Poly::opaque(format!("{}({})", f.name(), arg.print(names))),
    }
}
