//! Vehicle parameters, as the hand model reads them.

/// The physical parameters of every vehicle model (SI units; docs/src/conventions.md). Field names follow
/// the TOML keys (`I1` → `i1`, `R` → `r`, `J_a` → `j_a`, ...). Inertias are principal moments
/// `[Ixx, Iyy, Izz]` about the body's own centroid. File loading lives elsewhere; this is a plain
/// value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleParams {
    /// Base mass (body + rider) (kg); vehicle8/vehicle7 only.
    pub m1: f64,
    /// Pendulum mass (kg).
    pub m2: f64,
    /// Gravity (m/s²).
    pub g: f64,
    /// Base centroid height above the hinge (m); enters only the potential energy constant.
    pub a: f64,
    /// Pendulum centroid distance from the hinge (l) (m).
    pub b: f64,
    /// Track width (m); segway7 only (wheel positions).
    pub c: f64,
    /// Base inertia about its centroid (kg m²); only `i1[2]` (Izz) enters.
    pub i1: [f64; 3],
    /// Pendulum inertia about its centroid (kg m²).
    pub i2: [f64; 3],
    /// Wheel radius (m); segway7 only.
    pub r: f64,
    /// Mass of one wheel (kg); segway7 only.
    pub m_w: f64,
    /// Axial inertia of one wheel (kg m²); segway7 only.
    pub j_a: f64,
    /// Diametral inertia of one wheel (kg m²); segway7 only.
    pub j_d: f64,
}

/// Parameter names in the IR's parameter-vector order (inertias split into components).
pub const PARAM_NAMES: [&str; 16] = [
    "m1", "m2", "g", "a", "b", "c", "I1_xx", "I1_yy", "I1_zz", "I2_xx", "I2_yy", "I2_zz", "R",
    "m_w", "J_a", "J_d",
];

impl VehicleParams {
    /// Builds the parameters from the IR's parameter vector (order [`PARAM_NAMES`]), so that the
    /// audit can hand both routes the very same numbers.
    pub const fn from_array(p: [f64; 16]) -> Self {
        Self {
            m1: p[0],
            m2: p[1],
            g: p[2],
            a: p[3],
            b: p[4],
            c: p[5],
            i1: [p[6], p[7], p[8]],
            i2: [p[9], p[10], p[11]],
            r: p[12],
            m_w: p[13],
            j_a: p[14],
            j_d: p[15],
        }
    }

    /// The IR's parameter vector (order [`PARAM_NAMES`]).
    pub const fn to_array(&self) -> [f64; 16] {
        [
            self.m1, self.m2, self.g, self.a, self.b, self.c, self.i1[0], self.i1[1], self.i1[2],
            self.i2[0], self.i2[1], self.i2[2], self.r, self.m_w, self.j_a, self.j_d,
        ]
    }
}
