//! The study's pitch loop: F = Kp Φ + Ki ∫Φ dt + Kd Φ̇ driving the input direction `b_dir`
//! (u = b_dir · F; for the force models b_dir = (1, 0) puts F on F1, for `segway7` the caller
//! chooses the split of F between τ_L and τ_R), optionally through an actuator lag 1/(τs + 1)
//! and a delay e^{−sT}.
//!
//! Sign convention: the study's law pushes the base *towards* the lean (F = +Kp Φ), positive
//! feedback on Φ. In the negative-feedback convention the margins are defined in, the return
//! ratio broken at the actuator is therefore L(s) = −C(s) P(s), P = c (sI − A)⁻¹ B b_dir the
//! transfer from F to Φ, and the closed-loop poles are the zeros of 1 + L(s).

use nalgebra::{Complex, DMatrix, DVector, RowDVector};

use super::error::{check_finite, LinearError};
use super::linearize::{state_index, PHI, PITCH_RATE};
use super::modes::{eigenvalues, spectral_abscissa, zero_tolerance};
use super::siso::{HiddenPart, SisoPlant};

/// PID gains of F = Kp Φ + Ki ∫Φ + Kd Φ̇ (N/rad, N/(rad s), N s/rad for a force input).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PidGains {
    /// Proportional gain.
    pub kp: f64,
    /// Integral gain; 0 means a PD law (no integrator state).
    pub ki: f64,
    /// Derivative gain (on the measured pitch rate w_y).
    pub kd: f64,
}

impl PidGains {
    /// A PD law.
    pub fn pd(kp: f64, kd: f64) -> Self {
        Self { kp, ki: 0.0, kd }
    }

    fn check(&self) -> Result<(), LinearError> {
        check_finite("PID gains", [self.kp, self.ki, self.kd].iter())
    }
}

/// What sits between the controller and the vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopOptions {
    /// First-order actuator lag time constant τ (s); 0 = none.
    pub lag: f64,
    /// Pure delay T (s); 0 = none.
    pub delay: f64,
}

impl LoopOptions {
    /// Rejects NaN and negative times.
    pub fn check(&self) -> Result<(), LinearError> {
        for (what, v) in [("actuator lag", self.lag), ("delay", self.delay)] {
            if !v.is_finite() {
                return Err(LinearError::NonFinite { what });
            }
            if v < 0.0 {
                return Err(LinearError::Negative { what, value: v });
            }
        }
        Ok(())
    }

    /// The lag and delay factor 1/(τ jω + 1) · e^{−jωT} at s = jω.
    pub fn factor(&self, w: f64) -> Complex<f64> {
        let lag = Complex::new(1.0, self.lag * w).inv();
        lag * Complex::from_polar(1.0, -w * self.delay)
    }
}

/// The linearised vehicle with the pitch loop's input and measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct PitchLoop {
    a: DMatrix<f64>,
    b: DVector<f64>,
    phi: usize,
    rate: usize,
    states: Vec<String>,
    plant: SisoPlant,
}

/// Closed-loop eigenvalues, split into what the pitch loop moves and what it cannot.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClosedLoop {
    /// Poles of the loop itself: the minimal plant with the controller (and lag) states.
    pub loop_eigenvalues: Vec<Complex<f64>>,
    /// Largest real part of `loop_eigenvalues`.
    pub spectral_abscissa: f64,
    /// True when every loop eigenvalue has Re < 0 (delay not included: see
    /// [`super::margins::Margins::stable`]).
    pub stable: bool,
    /// Modes the loop cannot move or see (the uncontrolled drift x, v_x, y, θ, … of a
    /// vehicle); their eigenvalues are the open-loop ones.
    pub hidden: Vec<HiddenPart>,
    /// Eigenvalues of the full closed-loop matrix (`loop_eigenvalues` ∪ hidden).
    pub all_eigenvalues: Vec<Complex<f64>>,
}

/// Closed-loop matrix of ẋ = A x + b F with the PID law on y = c_phi x, ẏ = c_rate x; state
/// (x, [∫Φ if Ki ≠ 0], [F if τ > 0]). One assembly serves the full model and its minimal
/// realisation, so both spectra come from the same law.
fn assemble(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    c_phi: &RowDVector<f64>,
    c_rate: &RowDVector<f64>,
    g: &PidGains,
    lag: f64,
) -> DMatrix<f64> {
    let n = a.nrows();
    let integ = g.ki != 0.0;
    let iz = n;
    let i_f = n + usize::from(integ);
    let size = i_f + usize::from(lag > 0.0);
    let mut m = DMatrix::zeros(size, size);
    m.view_mut((0, 0), (n, n)).copy_from(a);
    // The commanded force as a row over the closed-loop state.
    let mut law = RowDVector::zeros(size);
    for j in 0..n {
        law[j] = g.kp * c_phi[j] + g.kd * c_rate[j];
    }
    if integ {
        law[iz] = g.ki;
        for j in 0..n {
            m[(iz, j)] = c_phi[j];
        }
    }
    if lag > 0.0 {
        // ẋ = A x + b F, Ḟ = (law − F)/τ.
        for i in 0..n {
            m[(i, i_f)] += b[i];
        }
        for j in 0..size {
            m[(i_f, j)] = law[j] / lag;
        }
        m[(i_f, i_f)] -= 1.0 / lag;
    } else {
        for i in 0..n {
            for j in 0..size {
                m[(i, j)] += b[i] * law[j];
            }
        }
    }
    m
}

impl PitchLoop {
    /// Builds the loop from A (n × n), the input matrix B (n × m) and the input direction
    /// `b_dir` (length m); `states` names the states and must contain `phi` and `w_y`.
    pub fn new(
        a: &DMatrix<f64>,
        b_u: &DMatrix<f64>,
        b_dir: &[f64],
        states: &[String],
    ) -> Result<Self, LinearError> {
        let n = a.nrows();
        if a.ncols() != n || b_u.nrows() != n {
            return Err(LinearError::Dimension {
                what: "A and B rows",
                expected: n,
                got: if a.ncols() != n {
                    a.ncols()
                } else {
                    b_u.nrows()
                },
            });
        }
        if b_dir.len() != b_u.ncols() {
            return Err(LinearError::Dimension {
                what: "input direction b_dir",
                expected: b_u.ncols(),
                got: b_dir.len(),
            });
        }
        check_finite("input direction", b_dir.iter())?;
        check_finite("B", b_u.iter())?;
        let b = b_u * DVector::from_column_slice(b_dir);
        let phi = state_index(states, PHI)?;
        let rate = state_index(states, PITCH_RATE)?;
        // Kd w_y is Kd Φ̇ only if Φ̇ = w_y exactly.
        let tol = 1e-12 * a.amax().max(1.0);
        let row_ok = (0..n).all(|j| (a[(phi, j)] - f64::from(u8::from(j == rate))).abs() <= tol);
        if !row_ok || b[phi].abs() > tol {
            return Err(LinearError::NotPitchStructure { phi, rate });
        }
        let mut c = RowDVector::zeros(n);
        c[phi] = 1.0;
        let plant = SisoPlant::new(a, &b, &c, states)?;
        Ok(Self {
            a: a.clone(),
            b,
            phi,
            rate,
            states: states.to_vec(),
            plant,
        })
    }

    /// The SISO plant from F to Φ in minimal form.
    pub fn plant(&self) -> &SisoPlant {
        &self.plant
    }

    /// The state names.
    pub fn states(&self) -> &[String] {
        &self.states
    }

    /// Full closed-loop matrix, state (x, [∫Φ if Ki ≠ 0], [F if τ > 0]).
    pub fn closed_loop_matrix(
        &self,
        gains: &PidGains,
        opts: &LoopOptions,
    ) -> Result<DMatrix<f64>, LinearError> {
        gains.check()?;
        opts.check()?;
        let n = self.a.nrows();
        let mut c_phi = RowDVector::zeros(n);
        c_phi[self.phi] = 1.0;
        let mut c_rate = RowDVector::zeros(n);
        c_rate[self.rate] = 1.0;
        Ok(assemble(&self.a, &self.b, &c_phi, &c_rate, gains, opts.lag))
    }

    /// Closed-loop eigenvalues of the pitch loop (delay-free part) and of the hidden modes.
    pub fn closed_loop(
        &self,
        gains: &PidGains,
        opts: &LoopOptions,
    ) -> Result<ClosedLoop, LinearError> {
        let full = self.closed_loop_matrix(gains, opts)?;
        let (am, bm, cm) = self.plant.realization();
        // Φ̇ = c A x (+ c b F, which is zero: checked in `new`, and Markov parameters are
        // invariant under the reduction).
        let c_rate = cm * am;
        let small = assemble(am, bm, cm, &c_rate, gains, opts.lag);
        let loop_eigenvalues = eigenvalues(&small)?;
        let spectral_abscissa = spectral_abscissa(&loop_eigenvalues);
        let stable = spectral_abscissa < -zero_tolerance(&small) * 1e-6;
        Ok(ClosedLoop {
            loop_eigenvalues,
            spectral_abscissa,
            stable,
            hidden: self.plant.hidden().to_vec(),
            all_eigenvalues: eigenvalues(&full)?,
        })
    }

    /// The return ratio L(jω) = −C(jω) P(jω) · lag · delay (see the module doc for the sign);
    /// `None` at a pole on the imaginary axis (ω = 0 with an integrator).
    pub fn loop_response(
        &self,
        gains: &PidGains,
        opts: &LoopOptions,
        w: f64,
    ) -> Option<Complex<f64>> {
        Some(self.loop_delay_free(gains, opts.lag, w)? * Complex::from_polar(1.0, -w * opts.delay))
    }

    /// L(jω) without the delay factor.
    pub fn loop_delay_free(&self, gains: &PidGains, lag: f64, w: f64) -> Option<Complex<f64>> {
        let l = self.gain_basis(lag, w)?.response(gains)?;
        (l.re.is_finite() && l.im.is_finite()).then_some(l)
    }

    /// The loop's terms per unit gain at s = jω, delay-free (see [`GainBasis`]).
    pub fn gain_basis(&self, lag: f64, w: f64) -> Option<GainBasis> {
        let s = Complex::new(0.0, w);
        let p = -self.plant.eval(s)? * Complex::new(1.0, lag * w).inv();
        Some(GainBasis {
            p,
            i: (w != 0.0).then(|| p / s),
            d: p * s,
        })
    }
}

/// The loop is linear in the gains: L = Kp φ_p + Ki φ_i + Kd φ_d with φ_p = −P/(τs + 1),
/// φ_i = φ_p/s, φ_d = φ_p s at s = jω (delay-free). The tuner builds its linear constraints
/// from these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainBasis {
    /// φ_p.
    pub p: Complex<f64>,
    /// φ_i; `None` at ω = 0, where the integrator has its pole.
    pub i: Option<Complex<f64>>,
    /// φ_d.
    pub d: Complex<f64>,
}

impl GainBasis {
    /// Kp φ_p + Ki φ_i + Kd φ_d; `None` at ω = 0 with Ki ≠ 0 (L is infinite there).
    pub fn response(&self, g: &PidGains) -> Option<Complex<f64>> {
        let pd = self.p * g.kp + self.d * g.kd;
        if g.ki == 0.0 {
            Some(pd)
        } else {
            Some(pd + self.i? * g.ki)
        }
    }
}

impl PitchLoop {
    /// The pitch loop of a linearised model with input direction `b_dir` (u = b_dir · F).
    pub fn from_linearization<const NX: usize, const NU: usize>(
        lin: &super::linearize::Linearization<NX, NU>,
        b_dir: &[f64; NU],
    ) -> Result<Self, LinearError> {
        let (a, b) = lin.dynamic();
        Self::new(&a, &b, b_dir, &lin.states)
    }
}
