//! One FMU instance: the state of a model-exchange or co-simulation run, in safe Rust. The C
//! functions (`abi.rs`) only convert pointers and call these methods; every buffer a simulation
//! needs is allocated here, at instantiation, so no derivative, step or directional derivative
//! allocates.

use twv_ir::{ValueReferences, Variable};

use crate::plant::Loaded;

/// Where an instance is in the FMI 2.0 state machine (only what the checks need).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// After `fmi2Instantiate` (start values may be set).
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initializing,
    /// Simulating (event, continuous-time or step mode).
    Running,
    /// After `fmi2Terminate`, or after an error: only getters, reset and free.
    Stopped,
}

/// A failed call, said in one line (logged through the environment's logger).
pub type Refusal = String;

/// What `fmi2GetFMUstate` saves: everything that changes during a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    pub time: f64,
    pub x: Vec<f64>,
    pub u: Vec<f64>,
    pub p: Vec<f64>,
}

impl Snapshot {
    /// The values as bytes (`fmi2SerializeFMUstate`): little-endian f64s, time first.
    pub fn to_bytes(&self) -> Vec<u8> {
        std::iter::once(self.time)
            .chain(self.x.iter().copied())
            .chain(self.u.iter().copied())
            .chain(self.p.iter().copied())
            .flat_map(f64::to_le_bytes)
            .collect()
    }

    /// The values back from [`to_bytes`](Self::to_bytes), for a model of these sizes.
    pub fn from_bytes(bytes: &[u8], nx: usize, nu: usize, np: usize) -> Option<Self> {
        if bytes.len() != 8 * (1 + nx + nu + np) {
            return None;
        }
        let v: Vec<f64> = bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect();
        Some(Snapshot {
            time: v[0],
            x: v[1..1 + nx].to_vec(),
            u: v[1 + nx..1 + nx + nu].to_vec(),
            p: v[1 + nx + nu..].to_vec(),
        })
    }
}

/// An instance of the model.
pub struct Instance {
    pub model: Loaded,
    pub co_simulation: bool,
    pub phase: Phase,
    pub time: f64,
    pub x: Vec<f64>,
    pub u: Vec<f64>,
    pub p: Vec<f64>,
    /// The start values (what `fmi2Reset` returns to).
    start: Snapshot,
    refs: ValueReferences,
    dx: Vec<f64>,
    jac_x: Vec<f64>,
    jac_u: Vec<f64>,
    work: Vec<f64>,
    scratch: Vec<f64>,
    x_start: Vec<f64>,
}

impl Instance {
    /// A new instance at the start values: states and inputs zero, the exported parameters.
    pub fn new(model: Loaded, co_simulation: bool) -> Self {
        let (nx, nu) = (model.ir.nx(), model.ir.nu());
        let np = if model.tunable { model.ir.np() } else { 0 };
        let start = Snapshot {
            time: 0.0,
            x: vec![0.0; nx],
            u: vec![0.0; nu],
            p: model.params.clone(),
        };
        Instance {
            refs: ValueReferences { nx, nu, np },
            dx: vec![0.0; nx],
            jac_x: vec![0.0; nx * nx],
            jac_u: vec![0.0; nx * nu],
            work: vec![0.0; model.plant.work_len()],
            scratch: vec![0.0; twv_step::scratch_len(nx)],
            x_start: vec![0.0; nx],
            co_simulation,
            phase: Phase::Instantiated,
            time: start.time,
            x: start.x.clone(),
            u: start.u.clone(),
            p: start.p.clone(),
            start,
            model,
        }
    }

    /// Number of states.
    pub fn nx(&self) -> usize {
        self.x.len()
    }

    /// The values that change during a run.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            time: self.time,
            x: self.x.clone(),
            u: self.u.clone(),
            p: self.p.clone(),
        }
    }

    /// Returns to `s` (a snapshot of this model).
    pub fn restore(&mut self, s: &Snapshot) -> Result<(), Refusal> {
        if (s.x.len(), s.u.len(), s.p.len()) != (self.x.len(), self.u.len(), self.p.len()) {
            return Err("the FMU state is not one of this model".into());
        }
        self.time = s.time;
        self.x.copy_from_slice(&s.x);
        self.u.copy_from_slice(&s.u);
        self.p.copy_from_slice(&s.p);
        Ok(())
    }

    /// `fmi2Reset`: back to the start values, as after instantiation.
    pub fn reset(&mut self) {
        let start = self.start.clone();
        self.time = start.time;
        self.x = start.x;
        self.u = start.u;
        self.p = start.p;
        self.phase = Phase::Instantiated;
    }

    /// The sizes of a serialized state.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (self.x.len(), self.u.len(), self.p.len())
    }

    /// ẋ at the current point into `self.dx`.
    fn derivatives(&mut self) {
        let m = &self.model.plant;
        m.f(&self.p, &self.x, &self.u, &mut self.dx, &mut self.work);
    }

    /// `fmi2GetDerivatives`.
    pub fn get_derivatives(&mut self, out: &mut [f64]) -> Result<(), Refusal> {
        if out.len() != self.nx() {
            return Err(format!(
                "{} derivatives asked for, the model has {} states",
                out.len(),
                self.nx()
            ));
        }
        self.derivatives();
        out.copy_from_slice(&self.dx);
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "the derivative of {} is not finite at t = {} (the state left the model's domain)",
                self.model.ir.states()[i].name,
                self.time
            ));
        }
        Ok(())
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Refusal> {
        if vrs
            .iter()
            .any(|&vr| matches!(self.refs.variable(vr), Some(Variable::Derivative(_))))
        {
            self.derivatives();
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            *slot = match self.refs.variable(vr) {
                Some(Variable::State(i)) => self.x[i],
                Some(Variable::Derivative(i)) => self.dx[i],
                Some(Variable::Input(j)) => self.u[j],
                Some(Variable::Param(k)) => self.p[k],
                None => return Err(format!("no Real variable has value reference {vr}")),
            };
        }
        Ok(())
    }

    /// `fmi2SetReal`: states before or during a run (model exchange sets them through
    /// `fmi2SetContinuousStates`), inputs at any time, tunable parameters.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Refusal> {
        for (&vr, &v) in vrs.iter().zip(values) {
            let var = self.refs.variable(vr);
            let name = self.variable_name(vr);
            if !v.is_finite() {
                return Err(format!("{name} = {v}: not a finite number"));
            }
            match var {
                Some(Variable::State(i)) => self.x[i] = v,
                Some(Variable::Input(j)) => self.u[j] = v,
                Some(Variable::Param(k)) => {
                    let mut p = self.p.clone();
                    p[k] = v;
                    twv_ir::check_values(&p, "parameter", self.model.ir.params())
                        .map_err(|e| e.to_string())?;
                    self.p[k] = v;
                }
                Some(Variable::Derivative(_)) => {
                    return Err(format!("{name} is calculated: it cannot be set"))
                }
                None => return Err(format!("no Real variable has value reference {vr}")),
            }
        }
        Ok(())
    }

    /// The model description's name of value reference `vr`.
    pub fn variable_name(&self, vr: u32) -> String {
        let ir = &self.model.ir;
        match self.refs.variable(vr) {
            Some(Variable::State(i)) => ir.states()[i].name.clone(),
            Some(Variable::Derivative(i)) => format!("der({})", ir.states()[i].name),
            Some(Variable::Input(j)) => ir.inputs()[j].name.clone(),
            Some(Variable::Param(k)) => ir.params()[k].name.clone(),
            None => format!("value reference {vr}"),
        }
    }

    /// `fmi2SetContinuousStates`.
    pub fn set_states(&mut self, x: &[f64]) -> Result<(), Refusal> {
        if x.len() != self.nx() {
            return Err(format!(
                "{} states given, the model has {}",
                x.len(),
                self.nx()
            ));
        }
        self.x.copy_from_slice(x);
        Ok(())
    }

    /// `fmi2GetDirectionalDerivative`: Σ_j ∂unknown/∂known_j · dv_j, with the unknowns
    /// derivatives or states (the outputs) and the knowns states or inputs, from the model's
    /// Jacobian kernels at the current point.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), Refusal> {
        let (nx, nu) = (self.nx(), self.u.len());
        let m = &self.model.plant;
        m.jac_x(&self.p, &self.x, &self.u, &mut self.jac_x, &mut self.work);
        m.jac_u(&self.p, &self.x, &self.u, &mut self.jac_u, &mut self.work);
        for (&un, out) in unknowns.iter().zip(dv_unknown.iter_mut()) {
            let mut sum = 0.0;
            for (&kn, &dv) in knowns.iter().zip(dv_known) {
                let d = match (self.refs.variable(un), self.refs.variable(kn)) {
                    (Some(Variable::Derivative(i)), Some(Variable::State(j))) => {
                        self.jac_x[i * nx + j]
                    }
                    (Some(Variable::Derivative(i)), Some(Variable::Input(k))) => {
                        self.jac_u[i * nu + k]
                    }
                    (Some(Variable::State(i)), Some(Variable::State(j))) => {
                        f64::from(u8::from(i == j))
                    }
                    (Some(Variable::State(_)), Some(Variable::Input(_))) => 0.0,
                    _ => {
                        return Err(format!(
                            "no directional derivative of {} with respect to {}: unknowns are \
                             derivatives or states, knowns states or inputs",
                            self.variable_name(un),
                            self.variable_name(kn)
                        ))
                    }
                };
                sum += d * dv;
            }
            *out = sum;
        }
        Ok(())
    }

    /// `fmi2DoStep`: equal RK4 steps of at most the exported step over `[t, t + h]` with the
    /// inputs held; a state that stops being finite fails the step and leaves the state at its
    /// start.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), Refusal> {
        if !(h.is_finite() && h >= 0.0) {
            return Err(format!("communication step {h}: not a step size ≥ 0"));
        }
        if (t - self.time).abs() > 1e-9 * t.abs().max(1.0) {
            return Err(format!(
                "the step starts at t = {t} but the FMU is at t = {}",
                self.time
            ));
        }
        if h == 0.0 {
            return Ok(());
        }
        let (n, hs) = twv_step::equal_steps(h, self.model.rk4_step);
        self.x_start.copy_from_slice(&self.x);
        let (plant, p, u, work) = (&self.model.plant, &self.p, &self.u, &mut self.work);
        for _ in 0..n {
            let f = |x: &[f64], out: &mut [f64]| plant.f(p, x, u, out, work);
            if !twv_step::rk4_step(f, &mut self.x, hs, &mut self.scratch) {
                let at = self.time;
                self.x.copy_from_slice(&self.x_start);
                return Err(format!(
                    "the state stopped being finite in the step from t = {at} (h = {h})"
                ));
            }
        }
        self.time = t + h;
        Ok(())
    }
}
