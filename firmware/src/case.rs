//! One fixed computation of the C API, printed as the bits of its results: f, ∂f/∂x and ∂f/∂u
//! of vehicle8 at a point, the law's force there, and the state after a number of RK4 steps of
//! the closed loop. `.ci/cortex-m-test.sh` runs it on the host (`examples/case.rs`) and on an
//! emulated Cortex-M4 (`firmware/qemu`) and compares the two outputs: same bits on both CPUs.
//!
//! A case is one line of `key=value` words (values of vectors comma-separated):
//! `x=0.1,0,0,0,0,0,0,0 u=0,0 kp=3000 kd=900 amplitude=0.03 f_max=inf h=0.001 steps=2000`;
//! the parameters are the IR's defaults unless `p=...` gives all of them.

use core::fmt::Write;

use crate::c_api::{self, NP, NU, NX};
use crate::pd::PitchPd;

/// A parsed case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// Parameter values.
    pub p: [f64; NP],
    /// The state.
    pub x: [f64; NX],
    /// The input of the open-loop evaluations.
    pub u: [f64; NU],
    /// The closed loop's law.
    pub pd: PitchPd,
    /// RK4 step [s].
    pub h: f64,
    /// Number of RK4 steps.
    pub steps: u32,
}

/// What is wrong with a case's text: the word it could not read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BadWord<'a>(pub &'a str);

fn vector<'a, const N: usize>(word: &'a str, text: &'a str) -> Result<[f64; N], BadWord<'a>> {
    let mut out = [0.0; N];
    let mut items = text.split(',');
    for slot in out.iter_mut() {
        *slot = items
            .next()
            .and_then(|v| v.trim().parse().ok())
            .ok_or(BadWord(word))?;
    }
    match items.next() {
        None => Ok(out),
        Some(_) => Err(BadWord(word)),
    }
}

impl Case {
    /// The case of `text`; every key but `p` must be given.
    pub fn parse(text: &str) -> Result<Case, BadWord<'_>> {
        let mut case = Case {
            p: twv_generated::Vehicle8::DEFAULTS,
            x: [f64::NAN; NX],
            u: [f64::NAN; NU],
            pd: PitchPd {
                kp: f64::NAN,
                kd: f64::NAN,
                setpoint_amplitude: f64::NAN,
                f_max: f64::NAN,
            },
            h: f64::NAN,
            steps: 0,
        };
        let mut seen = 0u32;
        for word in text.split_whitespace() {
            let (key, value) = word.split_once('=').ok_or(BadWord(word))?;
            let number = || value.parse::<f64>().map_err(|_| BadWord(word));
            let bit = match key {
                "p" => {
                    case.p = vector(word, value)?;
                    0
                }
                "x" => {
                    case.x = vector(word, value)?;
                    1
                }
                "u" => {
                    case.u = vector(word, value)?;
                    2
                }
                "kp" => {
                    case.pd.kp = number()?;
                    4
                }
                "kd" => {
                    case.pd.kd = number()?;
                    8
                }
                "amplitude" => {
                    case.pd.setpoint_amplitude = number()?;
                    16
                }
                "f_max" => {
                    case.pd.f_max = number()?;
                    32
                }
                "h" => {
                    case.h = number()?;
                    64
                }
                "steps" => {
                    case.steps = value.parse().map_err(|_| BadWord(word))?;
                    128
                }
                _ => return Err(BadWord(word)),
            };
            seen |= bit;
        }
        if seen != 255 {
            return Err(BadWord(
                "(a key is missing: x u kp kd amplitude f_max h steps)",
            ));
        }
        Ok(case)
    }

    /// Runs the case through the C API and writes one line per result: its name, then each
    /// value's bits in hexadecimal; the RK4 line ends with the function's status.
    pub fn run(&self, out: &mut impl Write) -> core::fmt::Result {
        let (p, x, u) = (self.p.as_ptr(), self.x.as_ptr(), self.u.as_ptr());
        let mut f = [0.0; NX];
        let mut jac_x = [0.0; NX * NX];
        let mut jac_u = [0.0; NX * NU];
        let mut state = self.x;
        // SAFETY: every array has the length the C API reads or writes.
        let (force, rk4) = unsafe {
            c_api::twv_vehicle8_f(p, x, u, f.as_mut_ptr());
            c_api::twv_vehicle8_jac_x(p, x, u, jac_x.as_mut_ptr());
            c_api::twv_vehicle8_jac_u(p, x, u, jac_u.as_mut_ptr());
            let force = c_api::twv_pitch_pd_force(&self.pd, x);
            let status =
                c_api::twv_vehicle8_pd_rk4(p, &self.pd, state.as_mut_ptr(), self.h, self.steps);
            (force, status)
        };
        line(out, "f", &f)?;
        line(out, "jac_x", &jac_x)?;
        line(out, "jac_u", &jac_u)?;
        line(out, "force", &[force])?;
        line(out, "rk4", &state)?;
        writeln!(out, "status {rk4}")
    }
}

/// `name` and the bits of `values`.
fn line(out: &mut impl Write, name: &str, values: &[f64]) -> core::fmt::Result {
    out.write_str(name)?;
    for v in values {
        write!(out, " {:016x}", v.to_bits())?;
    }
    out.write_char('\n')
}
